#include "stimulus_side.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <thread>

#include "hapticlab/db/timing.hpp"
#include "hapticlab/runner/audit.hpp"

namespace hapticlab::runner::internal {

renderer::RenderOptions MethodOptions(const protocols::Method& m, std::uint64_t seed) {
  renderer::RenderOptions o;
  o.algorithm = renderer::ParseForceAlgorithm(m.algorithm);
  o.vibration = m.vibration;
  o.hybrid_filter = m.hybrid_filter;
  o.force_rate_hz = 1000;
  o.vibration_rate_hz = 10000;
  o.seed = seed;
  return o;
}

void SaveTiming(db::Database& database, std::int64_t trial_id, int attempt, const std::string& side,
                const renderer::RenderOptions& ro, const RtEngine& engine) {
  const EngineStats st = engine.Stats();
  const EngineTiming tm = engine.Timing();
  for (int loop = 0; loop < 2; ++loop) {
    const bool force = loop == 0;
    const LoopTiming& lt = force ? st.force_timing : st.vibration_timing;
    if (!force && lt.ticks == 0) continue;
    const RtThreadReport& th = force ? st.force_thread : st.vibration_thread;
    db::SideTiming r;
    r.trial_id = trial_id;
    r.attempt = attempt;
    r.side = side;
    r.loop = force ? "force" : "vibration";
    r.clock = st.virtual_clock ? "virtual" : "real";
    r.rate_hz = force ? ro.force_rate_hz : ro.vibration_rate_hz;
    r.achieved_rate_hz = force ? st.achieved_force_rate_hz : st.achieved_vibration_rate_hz;
    r.ticks = static_cast<std::int64_t>(lt.ticks);
    r.deadline_misses = static_cast<std::int64_t>(lt.misses);
    r.late_p50_us = lt.late_p50_s * 1e6;
    r.late_p99_us = lt.late_p99_s * 1e6;
    r.late_p999_us = lt.late_p999_s * 1e6;
    r.late_max_us = lt.late_max_s * 1e6;
    r.tick_p50_us = lt.tick_p50_s * 1e6;
    r.tick_p99_us = lt.tick_p99_s * 1e6;
    r.tick_p999_us = lt.tick_p999_s * 1e6;
    r.tick_max_us = lt.tick_max_s * 1e6;
    r.late_histogram = (force ? tm.force_late : tm.vibration_late).Sparse();
    r.recording_overflows = force ? static_cast<std::int64_t>(st.recording_overflows) : 0;
    r.audio_underruns = force ? 0 : static_cast<std::int64_t>(st.audio_underruns);
    r.priority = st.virtual_clock ? "virtual clock" : th.priority_status;
    r.memory_locked = st.memory.locked;
    r.timer_slack_ns = st.virtual_clock ? -1 : th.timer_slack_ns;
    db::SaveSideTiming(database, r);
  }
}

namespace {

// The console's live frame: the newest recorded rows (the writer's copy, never the engine's
// queue) and the engine's counters, read on this (the runner's) thread.
LiveFrame LiveOf(const RtEngine& engine, db::TrajectoryStream* fs, db::TrajectoryStream* vs,
                 const db::Trial& t, int screen_side, const std::string& stimulus, bool final) {
  LiveFrame f;
  f.plan_number = t.plan_index + 1;
  f.side = screen_side;
  f.stimulus = stimulus;
  f.final = final;
  db::TrajectorySample row{};
  if (fs && fs->Latest(&row)) {
    f.force_recorded = true;
    f.force_t_s = row.t_s;
    std::copy_n(row.values.begin(), f.force.size(), f.force.begin());
  }
  if (vs && vs->Latest(&row)) {
    f.vibration_recorded = true;
    f.vibration_t_s = row.t_s;
    f.vibration_mps2 = row.values[0];
  }
  f.engine = engine.Stats();
  return f;
}

// The render options of one side: a real sample only measured (force held at zero), a virtual
// one rendered within the device's limits.
renderer::RenderOptions SideOptions(const StimulusSide& side, const Rig& rig) {
  renderer::RenderOptions ro;
  if (side.real) {
    // The real sample under the stylus: the device only measures; its force is held at zero.
    ro.vibration = false;
    ro.max_force_N = 1e-9;
  } else {
    ro = side.options;
    const auto caps = rig.device->Capabilities();
    ro.max_force_N = std::min(ro.max_force_N, caps.max_force_N);
    ro.device_max_stiffness_N_per_m =
        caps.max_stiffness_N_per_m;  // base stiffness: half of it (ch. V)
  }
  return ro;
}

// Plays a started engine for `dur` seconds: at once on a virtual clock without screens, else in
// stimulus frames for the screens (on a virtual clock, time runs ui_playback_speed times faster
// than the wall clock). False when the screens abort the stimulus.
bool PlayStimulus(RtEngine& engine, const StimulusSide& side, const TrialContext& c, double dur,
                  const db::Trial& t, const TrialScreen& screen, int screen_side,
                  db::TrajectoryStream* fs, db::TrajectoryStream* vs) {
  const RunOptions& opt = c.opt;
  if (engine.is_virtual() && !opt.ui) {
    engine.AdvanceTo(dur);
    return true;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const double speed = c.participant.PlaybackSpeed();
  for (;;) {
    const double el = std::min(
        dur, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * speed);
    if (engine.is_virtual() && !engine.AdvanceTo(el)) break;
    const auto s = engine.LastSample();
    if (opt.ui) opt.ui->Live(LiveOf(engine, fs, vs, t, screen_side, side.stimulus, false));
    if (opt.ui && !opt.ui->Stimulus(screen, screen_side, s.state.p_m, dur - el)) return false;
    if (el >= dur) break;
    if (!opt.ui) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// The watchdog's faults of a side as events, its timing saved, and the side judged: faulted
// (the watchdog tripped) or untouched (the stylus too rarely inside the surface).
void RecordSideEnd(RtEngine& engine, const StimulusSide& side, const TrialContext& c,
                   const db::Trial& t, const renderer::RenderOptions& ro, bool injected,
                   SideOutcome* out) {
  db::Database& database = c.database;
  FaultEvent e;
  while (engine.watchdog().PopEvent(&e))
    database.LogEvent({.session_id = c.session,
                       .trial_id = t.id,
                       .kind = db::EventKind::kDeviceFault,
                       .detail = fmt::format("{} at {:.3f} s ({}, tick {})", FaultName(e.kind),
                                             e.t_s, side.label, e.tick),
                       .established_by = source::Watchdog(c.opt.device, injected)});
  const auto st = engine.Stats();
  out->stats = st;
  SaveTiming(database, t.id, database.CurrentAttempt(t.id), side.stream, ro, engine);
  if (engine.watchdog().tripped()) {
    out->fault = true;
    out->detail = fmt::format(
        "{}: {} disconnects, {} NaN, {} stale, {} missed-deadline, {} vibration-model "
        "faults",
        side.label, st.disconnects, st.nan_faults, st.stale_faults, st.miss_faults,
        st.vibration_faults);
  } else if (static_cast<double>(st.contact_ticks) <
             kMinContactFraction * static_cast<double>(st.force_ticks)) {
    out->untouched = true;
    out->detail = fmt::format("{} ({}): the stylus was inside the surface on {} of {} ticks",
                              side.label, side.stimulus, st.contact_ticks, st.force_ticks);
  }
}

}  // namespace

SideOutcome RunStimulusSide(const StimulusSide& side, const TrialContext& c, Rng& rng,
                            double duration_s, const db::Trial& t, const TrialScreen& screen,
                            int screen_side) {
  SideOutcome out;
  const double dur = duration_s;
  const auto sample = static_cast<std::size_t>(side.sample);
  Rig& rig = c.rig;
  const RunOptions& opt = c.opt;
  db::TrajectoryWriter* writer = c.writer;
  const renderer::MaterialModel& model = *side.model;
  renderer::RenderOptions ro = SideOptions(side, rig);
  renderer::HybridRenderer r(model, ro);
  // The participant takes the stylus: the simulated hand strokes the sample where it truly
  // is (on a real side its ground truth); a person at the rig explores by themselves.
  const bool injected = c.participant.BeginSide(side.report_side,
                                                {.sample = side.sample,
                                                 .real = side.real,
                                                 .material = side.material,
                                                 .model = &model,
                                                 .options = &ro},
                                                rng);
  db::TrajectoryStream *fs = nullptr, *vs = nullptr;
  if (writer && opt.record != RecordMode::kNone)
    fs = writer->OpenStream(t.id, side.stream + "_force", ro.force_rate_hz, ForceStreamChannels());
  if (writer && opt.record == RecordMode::kAll && ro.vibration && rig.actuator)
    vs = writer->OpenStream(t.id, side.stream + "_vibration", ro.vibration_rate_hz,
                            VibrationStreamChannels());
  EngineOptions eo;
  eo.virtual_clock = c.participant.Clock();
  eo.rt = opt.rt;
  eo.sample_from_device = rig.device_from_sample[sample].inverse();
  RtEngine engine(r, *rig.device, ro.vibration ? rig.actuator : nullptr, eo, fs, vs);
  engine.Start();
  const bool go_on = PlayStimulus(engine, side, c, dur, t, screen, screen_side, fs, vs);
  engine.Stop();
  if (opt.ui) opt.ui->Live(LiveOf(engine, fs, vs, t, screen_side, side.stimulus, true));
  if (fs) writer->CloseStream(fs);
  if (vs) writer->CloseStream(vs);
  RecordSideEnd(engine, side, c, t, ro, injected, &out);
  const SideFelt felt = c.participant.EndSide();
  if (opt.on_side)
    opt.on_side({.plan_index = t.plan_index,
                 .side = side.report_side,
                 .attempt = t.attempts,
                 .stimulus = side.stimulus,
                 .engine = out.stats,
                 .hand_ticks = felt.hand_ticks,
                 .contact_ticks = out.stats.contact_ticks});
  out.felt = felt.felt;
  out.aborted = !go_on;
  return out;
}

}  // namespace hapticlab::runner::internal
