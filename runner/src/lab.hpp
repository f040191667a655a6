#pragma once
// The lab of a session (private to runner): every material's model and the ground truth of
// each sample, loaded from the files a protocol names.

#include <map>
#include <optional>
#include <string>

#include "hapticlab/core/enum_names.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::runner::internal {

// Everything a session needs besides the database: models, profiles, observer.
struct Lab {
  const protocols::Protocol* protocol = nullptr;  // borrowed
  sim::ProfileSet profiles;
  std::map<std::string, renderer::MaterialModel> models;  // by material id
  std::map<std::string, std::string> model_hashes;  // by material id: SHA-256 of the model text
  std::map<std::string, std::string> model_texts;   // by material id: the text hashed
};

// Loads the profiles (ground truth of each sample) and every material's model. Files are
// looked up relative to the protocol file's folder. Every problem is collected (file, line,
// key, and the path looked up), then thrown together as one InputError: `study validate`
// reports the same. `model_files` (material id -> model file) replace the protocol's models
// (RunOptions::model_files).
Lab LoadLab(const protocols::Protocol& p, const std::string& device,
            const std::map<std::string, std::string>& model_files = {});

inline bool IsTraining(PhaseKind phase) { return phase == PhaseKind::kTraining; }

// One stimulus of a plan ("real:Denim", "virtual:Denim"): which kind, which material id.
struct Stimulus {
  bool real = false;
  std::string id;
};
// Splits "<kind>:<id>"; a string without a colon is the id of a virtual stimulus.
Stimulus ParseStimulus(const std::string& stimulus);

}  // namespace hapticlab::runner::internal
