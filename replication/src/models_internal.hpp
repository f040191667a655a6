#pragma once
// The files and material models of a protocol, as a plan holds them (private).

#include <map>
#include <string>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::replication::internal {

// A material model as the runner loads it (runner/src/lab.cpp): a model file's bytes, or a
// placeholder built from the sample's profile and written as TOML. The SHA-256 is the one a
// session records in its provenance ("model_hashes").
struct ModelText {
  std::string material, plan_file, sha256, source, text;
};

// Every material's model, in protocol order. @throws InputError as the runner's lab would
std::vector<ModelText> ModelsOf(const protocols::Protocol& p);

// "protocol/<file name>" -> the protocol's bytes, and "protocol/<path>" -> the bytes of every
// file it names (profiles, observer, models, and the files a model names: geometry,
// vibration, neural). @throws InputError naming the key when a path leaves the protocol's
// folder or a file cannot be read
std::map<std::string, std::string> ProtocolFiles(const protocols::Protocol& p);

}  // namespace hapticlab::replication::internal
