#pragma once
// `study run --plan` (cmd_study_plan.cpp): the protocol a run uses and what it records.

#include <string>

#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace hapticlab::cli {

/// Without `plan`: the protocol at `protocol` (required). With it: verifies the plan (or the
/// imported site directory), loads its protocol (or `protocol`, whose changed keys are printed
/// as deviations) and sets o's plan hash, site and substituted models.
/// @throws InputError naming every file of the plan that does not verify
protocols::Protocol LoadRunProtocol(const std::string& protocol, const std::string& plan,
                                    runner::RunOptions* o, bool quiet);

}  // namespace hapticlab::cli
