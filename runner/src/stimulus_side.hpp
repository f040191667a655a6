#pragma once
// One stimulus side through the one trial path (private to runner): the renderer for a model
// and render options inside RtEngine over the rig's device and actuator, with the watchdog
// and the trajectory writer; the session's Participant (participant.hpp) holds the stylus.
// Used by the
// planned trials (study_runner.cpp, each of a trial's two sides) and by the adaptive phases
// (adaptive_phase.cpp, each interval of a trial).

#include <cstdint>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "participant.hpp"

namespace hapticlab::runner::internal {

// A side in which the model found the stylus inside its surface on fewer ticks than this
// fraction touched nothing.
inline constexpr double kMinContactFraction = 0.05;

// The method's render options (rates 1 kHz force, 10 kHz vibration), before the device's
// limits are applied (RunStimulusSide does that for a virtual side).
renderer::RenderOptions MethodOptions(const protocols::Method& m, std::uint64_t seed);

// What one side (or interval) presents.
struct StimulusSide {
  const renderer::MaterialModel* model = nullptr;  // required (borrowed)
  // The method's options for a virtual side; for a real side ignored (the device only
  // measures: force held at zero, no vibration).
  renderer::RenderOptions options;
  bool real = false;
  std::string material;  // the material's id (a real side: the sample under the stylus)
  int sample = 0;        // which sample pose of the rig the side is on (0 left, 1 right)
  std::string stream;    // the recorded streams are <stream>_force and <stream>_vibration
  std::string label;     // how events and messages name it ("left side", "interval 2")
  std::string stimulus;  // what it is, for messages and SideReport ("virtual:Denim")
  int report_side = 0;   // SideReport::side and the side's index in its trial (the trial
                         // side, or the interval index)
};

// Where a trial's sides run: the session's rig and participant, its options, the trajectory
// writer (may be null) and the database.
struct TrialContext {
  Rig& rig;
  Participant& participant;
  const RunOptions& opt;
  db::TrajectoryWriter* writer;
  db::Database& database;
  std::int64_t session;
};

// What one side did.
struct SideOutcome {
  bool aborted = false;    // the experimenter aborted in the UI during the stimulus
  bool fault = false;      // the watchdog tripped (force was zeroed)
  bool untouched = false;  // the stylus was inside the surface on < kMinContactFraction of ticks
  std::string detail;      // for a fault or an untouched side: what happened
  EngineStats stats;
  sim::Features felt;  // what the hand felt (Participant::EndSide)
};

// Stores the engine's timing of one side (db::SideTiming rows: force, and vibration when it ran).
void SaveTiming(db::Database& database, std::int64_t trial_id, int attempt, const std::string& side,
                const renderer::RenderOptions& ro, const RtEngine& engine);

// Runs one side for `duration_s` on the context's rig, the participant holding the stylus
// (Participant::BeginSide, with the trial's generator `rng`, and EndSide): streams opened on
// the writer per opt.record (the vibration stream only when the side vibrates and the rig has
// an actuator), watchdog events logged as "device-fault" events of trial `t`, opt.on_side
// called. With opt.ui the stimulus frames (the engine's last sample) go to
// SessionUi::Stimulus with `screen` and `screen_side`, in real time (a virtual clock runs
// Participant::PlaybackSpeed times faster); at least one frame is shown.
SideOutcome RunStimulusSide(const StimulusSide& side, const TrialContext& c, Rng& rng,
                            double duration_s, const db::Trial& t, const TrialScreen& screen,
                            int screen_side);

}  // namespace hapticlab::runner::internal
