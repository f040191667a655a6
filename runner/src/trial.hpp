#pragma once
// One planned trial through the one trial path (private to runner): both sides (or the
// training sample) through RunStimulusSide, then the participant's ratings.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "lab.hpp"
#include "stimulus_side.hpp"

namespace hapticlab::runner::internal {

struct Outcome {
  bool aborted = false;  // the experimenter aborted in the UI
  bool fault = false;
  bool untouched = false;  // a side where the stylus never met the surface
  bool injected = false;   // the fault was injected by the simulation (--inject-faults)
  std::string fault_detail;
  std::vector<db::Rating> ratings;
  double stimulus_s = 0;
};

// A planned trial's stimuli, parsed once ("real:Denim": a real sample of material Denim);
// no right one for a training trial.
struct TrialStimuli {
  Stimulus left;
  std::optional<Stimulus> right;
};
TrialStimuli ParseStimuli(const db::Trial& t);

// The screen of planned trial `t`, the `index`-th (1-based) of `total`.
TrialScreen ScreenOf(const protocols::Protocol& p, const db::Trial& t, const TrialStimuli& stimuli,
                     int index, int total);

// Runs one trial, simulated or on hardware, through the one trial path: each side for the
// stimulus duration through RunStimulusSide (the method's renderer, or for a real sample
// zero force: the device only measures, inside the real-time engine over the rig's device
// and actuator, with the watchdog and the trajectory writer), the context's participant
// holding the stylus. A watchdog fault in either side faults the trial; a side that touched
// nothing is reported. Then the participant rates (Participant::Rate).
Outcome ExecuteTrial(const Lab& lab, const db::Trial& t, const TrialStimuli& stimuli,
                     std::uint64_t participant_seed, const TrialContext& c,
                     const TrialScreen& screen);

}  // namespace hapticlab::runner::internal
