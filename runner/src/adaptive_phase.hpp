#pragma once
// Adaptive phases (staircase, QUEST+) in a session: the runner's only entry point into them
// (study_runner.cpp calls RunAdaptivePhases after the planned phases). Private to runner.

#include <cstdint>
#include <map>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "stimulus_side.hpp"

namespace hapticlab::runner::internal {

struct AdaptiveOutcome {
  bool aborted = false;  // stopped (stop_after_trials); the session is marked aborted
  int added = 0;         // trial rows created
  int completed = 0, faults = 0;
  double stimulus_s = 0;  // stimulus time rendered
};

// Runs every adaptive phase of the protocol, in protocol order, continuing each from its
// recorded trials. `executed` counts trials run in this call of the session (for
// stop_after_trials) and is advanced. Every interval is presented through the one trial
// path (RunStimulusSide, stimulus_side.hpp) on the context's rig: the method's renderer in
// the real-time engine over the rig's device, the participant holding the stylus, streams
// i<k>_force and i<k>_vibration; the participant answers (Participant::Answer).
// @throws hapticlab::InputError for a hardware device (not supported yet) or a simulated
// session without a UI whose phase has no [phase.simulated_observer].
AdaptiveOutcome RunAdaptivePhases(const protocols::Protocol& p,
                                  const std::map<std::string, renderer::MaterialModel>& models,
                                  std::uint64_t participant_seed, const TrialContext& c,
                                  int* executed);

// The model with one parameter set to `value`; `parameter` is one of
// protocols::AdaptiveParameters() (PreconditionError otherwise).
renderer::MaterialModel WithParameter(const renderer::MaterialModel& m,
                                      const std::string& parameter, double value);

}  // namespace hapticlab::runner::internal
