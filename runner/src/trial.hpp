#pragma once
// One planned trial through the one trial path (private to runner): both sides (or the
// training sample) through RunStimulusSide, then the ratings from the participant window or
// the simulated observer.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "lab.hpp"

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

// The screen of planned trial `t`, the `index`-th (1-based) of `total`.
TrialScreen ScreenOf(const protocols::Protocol& p, const db::Trial& t, int index, int total);

// Runs one trial, simulated or on hardware, through the one trial path: each side for the
// stimulus duration through internal::RunStimulusSide (the method's renderer, or for a real
// sample zero force: the device only measures, inside the real-time engine over the rig's
// device and actuator, with the watchdog and the trajectory writer). A watchdog fault in
// either side faults the trial; a side that touched nothing is reported. Ratings come from
// the participant window, or on a simulated rig without one from the simulated observer
// rating what the hand felt.
Outcome ExecuteTrial(const Lab& lab, const sim::Observer& observer, const db::Trial& t,
                     std::uint64_t participant_seed, const RunOptions& opt, HardwareRig& rig,
                     db::TrajectoryWriter* writer, const TrialScreen& screen,
                     db::Database& database, std::int64_t session);

}  // namespace hapticlab::runner::internal
