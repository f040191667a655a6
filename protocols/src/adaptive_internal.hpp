#pragma once
// Parsing of adaptive phases (staircase, quest-plus), called by ParseProtocol.

#include <toml++/toml.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols::internal {

// Reads the keys of an adaptive [[phase]] table into ph->adaptive, adding every problem to
// `d` as file:line: phase[i].key: message. `p` has its materials and methods parsed.
void ParseAdaptivePhase(const toml::table& t, const std::string& prefix, const std::string& file,
                        const Protocol& p, Diagnostics* d, Phase* ph);

}  // namespace hapticlab::protocols::internal
