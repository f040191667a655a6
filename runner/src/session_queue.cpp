#include "session_queue.hpp"

#include <fmt/format.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>

#include "adaptive_phase.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/runner/audit.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "trial.hpp"

namespace hapticlab::runner::internal {
namespace {

using sim::Observer;

void Log(const RunOptions& o, const std::string& s) {
  if (o.log) o.log(s);
}
void Warn(const RunOptions& o, const std::string& s) {
  if (o.warn) o.warn(s);
}

// `text` (an error message) with the database's folder left out: the record holds no path
// that could carry a user or host name.
std::string WithoutFolder(const db::Database& database, std::string text) {
  const std::string name = std::filesystem::path(database.path()).filename().string();
  for (const std::string& path :
       {std::filesystem::absolute(database.path()).lexically_normal().string(), database.path()})
    for (std::size_t at; !path.empty() && (at = text.find(path)) != std::string::npos;)
      text.replace(at, path.size(), name);
  return text;
}

// Marks a session that stopped on an error (a full disk, a database that cannot be written,
// a device that failed to open) as 'failed', with a 'stopped' event saying why. On a full
// disk even that may fail: then the -wal is checkpointed (freeing its frames) and it is
// tried once more; failing that, the session stays 'running' and 'study resume' says so.
void MarkFailed(db::Database& database, std::int64_t session, const std::string& why,
                const RunOptions& opt) {
  const auto mark = [&] {
    database.Exec("BEGIN IMMEDIATE");
    try {
      database.LogEvent(
          {.session_id = session,
           .kind = "stopped",
           .detail = "the session stopped on an error: " + WithoutFolder(database, why) +
                     "; completed trials are recorded; fix the cause, then "
                     "'hapticlab study resume'",
           .established_by = source::kRunner});
      database.EndSession(session, kSessionFailed);
      database.Exec("COMMIT");
    } catch (...) {
      database.Exec("ROLLBACK");
      throw;
    }
  };
  for (int attempt = 0; attempt < 2; ++attempt) {
    try {
      mark();
      Warn(opt, fmt::format("session {} stopped on an error and is marked 'failed' (a 'stopped' "
                            "event says why); fix the cause, then 'hapticlab study resume'",
                            session));
      return;
    } catch (const std::exception&) {
      database.Checkpoint();
    }
  }
  Warn(opt, fmt::format("session {} could not be marked as stopped (the database cannot be "
                        "written); it stays 'running' until 'hapticlab study resume'",
                        session));
}

RunSummary Execute(db::Database& database, const Lab& lab, std::int64_t session,
                   const db::Participant& part, const RunOptions& opt);

}  // namespace

RunSummary ExecuteSession(db::Database& database, const Lab& lab, std::int64_t session,
                          const db::Participant& part, const RunOptions& opt) {
  try {
    return Execute(database, lab, session, part, opt);
  } catch (const std::exception& e) {
    MarkFailed(database, session, e.what(), opt);
    throw;
  }
}

namespace {

RunSummary Execute(db::Database& database, const Lab& lab, std::int64_t session,
                   const db::Participant& part, const RunOptions& opt) {
  const auto& p = *lab.protocol;
  const auto t0 = std::chrono::steady_clock::now();
  RunSummary sum;
  sum.session_id = session;
  sum.participant = part.code;
  // Every way a session ends goes through `finish`; every abort through `abort` (the reason
  // logged as an event of the session, the session closed as aborted).
  const auto finish = [&](const char* status) {
    sum.status = status;
    sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return sum;
  };
  const auto abort = [&](db::Event why) {
    why.session_id = session;
    if (why.kind.empty()) why.kind = "abort";
    database.LogEvent(why);
    database.EndSession(session, "aborted");
    return finish("aborted");
  };
  const Observer observer(lab.profiles.observer, DeriveSeed(part.seed, 0xABCDEF), p.criteria);
  // Without a rig, a simulated session builds the generic simulated rig.
  std::unique_ptr<sim::SimRig> own_sim;
  HardwareRig own_rig;
  HardwareRig* rig = opt.rig;
  if (!rig) {
    HL_REQUIRE(opt.device == "sim", "a session on device '" + opt.device +
                                        "' needs RunOptions::rig (the opened device)");
    own_sim = std::make_unique<sim::SimRig>(
        sim::SimDeviceModel{.seed = DeriveSeed(part.seed, 0x51D)}, sim::DefaultSamplePoses());
    own_rig.device = own_sim->device;
    own_rig.actuator = &own_sim->actuator;
    own_rig.device_from_sample = own_sim->true_device_from_sample;
    own_rig.sim = own_sim.get();
    own_rig.description = "sim (generic simulated device, simulated hand)";
    rig = &own_rig;
  }
  HL_REQUIRE(rig->device != nullptr, "RunOptions::rig has no device");
  HL_REQUIRE(rig->sim != nullptr || opt.ui != nullptr,
             "a hardware session needs RunOptions::ui (the participant window gives the ratings)");
  if (opt.device != "sim" || opt.rig)
    database.LogEvent({.session_id = session,
                       .kind = "device",
                       .detail = rig->description,
                       .established_by = source::Device(opt.device)});
  // Masking noise on the headphones for the whole session (ch. IV.5.1, V.2.1).
  struct Noise {
    devices::MaskingNoise* n;
    ~Noise() {
      if (n) n->SetNoiseLevel(0);
    }
  } noise{p.masking_noise ? rig->noise : nullptr};
  if (noise.n) noise.n->SetNoiseLevel(rig->noise_rms_fs);
  db::TrajectoryWriter writer(database.path());
  constexpr int kMaxTrajectoryFaults = 3;  // in a row: the disk or the database is the problem
  int trajectory_faults = 0;
  auto trials = database.Trials(session);
  sum.planned = static_cast<int>(trials.size());
  std::string last_material;
  for (const auto& t : trials)
    if (t.status == db::kTrialCompleted) {
      ++sum.completed;
      last_material = t.material;  // plan order: the last completed trial precedes the next
    }
  // The screens count rated trials of the planned phases (training apart), 1-based.
  int rated_total = 0, rated_done = 0, training_total = 0, training_done = 0;
  for (const auto& t : trials) {
    const bool training = t.phase == std::string("training");
    (training ? training_total : rated_total) += 1;
    if (t.status == db::kTrialCompleted) (training ? training_done : rated_done) += 1;
  }
  // The experimenter's actions in the console (pause, resume, abort asked / cancelled, a
  // break ended early) become session events, tied to the trial under way.
  std::optional<std::int64_t> trial_under_way;
  struct UiEvents {
    SessionUi* ui;
    ~UiEvents() {
      if (ui) ui->log_event = nullptr;
    }
  } ui_events{opt.ui};
  if (opt.ui)
    opt.ui->log_event = [&](const std::string& kind, const std::string& detail) {
      database.LogEvent({.session_id = session,
                         .trial_id = trial_under_way,
                         .kind = kind,
                         .detail = detail,
                         .established_by = source::kConsole});
    };
  // A faulted attempt of trial `t`: its cause as an event (established by `by`), then the
  // runner's re-queue as an 'attempt-faulted' event (counted by 'study status') and a line on
  // the log even without progress lines. The caller re-queues `t`.
  const auto requeue = [&](db::Trial& t, const char* kind, const std::string& cause,
                           const std::string& by) {
    ++sum.faults;
    database.SetTrialStatus(t.id, db::kTrialFaulted);
    database.LogEvent({.session_id = session,
                       .trial_id = t.id,
                       .kind = kind,
                       .detail = cause,
                       .established_by = by});
    std::string why = cause;  // the watchdog's text may end by saying it already
    for (const char* tail : {", trial re-queued", "; trial re-queued"})
      if (why.size() > std::strlen(tail) && why.ends_with(tail))
        why.resize(why.size() - std::strlen(tail));
    const std::string line =
        fmt::format("trial {} ({}, attempt {}) faulted: {}; re-queued at the end of the {} phase",
                    t.plan_index + 1, t.phase, t.attempts, why, t.phase);
    database.LogEvent({.session_id = session,
                       .trial_id = t.id,
                       .kind = "attempt-faulted",
                       .detail = line,
                       .established_by = source::kRunner});
    Warn(opt, part.code + ": " + line);
    t.status = db::kTrialFaulted;
  };
  const bool constrained = p.randomization.no_immediate_repeat;
  int untouched_in_a_row = 0;
  std::set<std::int64_t> break_before;  // trials the plan puts a break before
  std::set<std::int64_t> done;          // trials completed (before a resume or now)
  for (const auto& t : trials)
    if (t.status == db::kTrialCompleted) done.insert(t.id);
  for (const auto& e : database.Events(session))
    if (e.kind == "break-planned" && e.trial_id) break_before.insert(*e.trial_id);
  for (const char* phase : {"training", "reference", "main"}) {
    std::vector<db::Trial> queue;
    for (const auto& t : trials)
      if (t.phase == phase && t.status != db::kTrialCompleted && t.status != db::kTrialFaulted)
        queue.push_back(t);
    for (const auto& t : trials)  // faulted before a crash: retried at the phase's end
      if (t.phase == phase && t.status == db::kTrialFaulted) queue.push_back(t);
    while (!queue.empty()) {
      // Keep the no-immediate-repeat constraint for re-queued trials when possible.
      std::size_t pick = 0;
      if (constrained && queue[0].material == last_material && std::string(phase) != "training") {
        for (std::size_t i = 1; i < queue.size(); ++i)
          if (queue[i].material != last_material) {
            pick = i;
            break;
          }
        if (pick == 0 && queue.size() > 1)
          database.LogEvent({.session_id = session,
                             .trial_id = queue[0].id,
                             .kind = "constraint-relaxed",
                             .detail = "only trials of the same material remain in the phase",
                             .established_by = source::kRunner});
      }
      db::Trial t = queue[pick];
      queue.erase(queue.begin() + static_cast<std::ptrdiff_t>(pick));
      if (const int sig = StopRequested()) {
        return abort(
            {.trial_id = t.id,
             .kind = "interrupted",
             .detail = fmt::format("stopped by signal {} ({}) before this trial; 'study resume' "
                                   "continues with it",
                                   sig,
                                   sig == SIGINT    ? "SIGINT"
                                   : sig == SIGTERM ? "SIGTERM"
                                                    : "signal"),
             .established_by = source::kSignal});
      }
      if (opt.stop_after_trials >= 0 && sum.executed >= opt.stop_after_trials) {
        return abort({.detail = "stopped after the requested number of trials",
                      .established_by = source::CommandLine("--stop-after")});
      }
      // The console shows this trial as the next one from now on: through a break and while
      // its samples are placed.
      const bool training = t.phase == std::string("training");
      auto screen = ScreenOf(p, t, training ? training_done + 1 : rated_done + 1,
                             training ? training_total : rated_total);
      screen.training = training;
      screen.rated_done = rated_done;
      screen.rated_total = rated_total;
      screen.training_done = training_done;
      screen.training_total = training_total;
      screen.plan_total = sum.planned;
      screen.break_before = break_before.count(t.id) && !training;
      screen.breaks_left = 0;
      for (const auto& b : trials)
        if (break_before.count(b.id) && b.phase != std::string("training") && !done.count(b.id) &&
            b.id != t.id)
          ++screen.breaks_left;
      if (opt.ui) opt.ui->Upcoming(screen);
      const bool requested = opt.ui && opt.ui->TakeBreakNow();
      if (opt.ui &&
          (requested || (break_before.count(t.id) && t.phase != std::string("training")))) {
        // A simulated session played faster (--ui-speed) shortens its breaks alike.
        const double speed = rig->sim ? opt.ui_playback_speed : 1.0;
        const double break_s = p.break_duration_s / speed;
        database.LogEvent(
            {.session_id = session,
             .trial_id = t.id,
             .kind = "break",
             .detail =
                 fmt::format("{:.0f} s break ({}{})", break_s,
                             requested ? "requested by the experimenter" : "planned",
                             speed != 1.0 ? fmt::format("; played {:g} times faster", speed) : ""),
             .established_by = requested ? source::kConsole : source::kPlan});
        trial_under_way = t.id;
        if (!opt.ui->Break(break_s)) {
          return abort({.detail = "the experimenter aborted during a break",
                        .established_by = source::kConsole});
        }
      }
      if (opt.ui && screen.real_sample) {
        // No trial with a real sample starts before the experimenter confirms its samples.
        trial_under_way = t.id;
        const auto how = opt.ui->ConfirmPlacement(screen);
        if (!how) return abort({.detail = "the experimenter aborted while placing the samples"});
        database.LogEvent(
            {.session_id = session,
             .trial_id = t.id,
             .kind = "samples-placed",
             .detail = fmt::format("trial {}: {}; {}", screen.plan_number, screen.placement, *how),
             .established_by =
                 how->starts_with("not confirmed") ? source::kRunner : source::kConsole});
      }
      database.StartTrial(t.id);
      ++t.attempts;
      ++sum.executed;
      trial_under_way = t.id;
      const Outcome o =
          ExecuteTrial(lab, observer, t, part.seed, opt, *rig, &writer, screen, database, session);
      sum.simulated_s += o.stimulus_s;
      untouched_in_a_row = o.untouched ? untouched_in_a_row + 1 : 0;
      if (o.aborted) {
        return abort({.trial_id = t.id,
                      .detail = "the experimenter aborted in the console; 'study resume' continues "
                                "with this trial",
                      .established_by = source::kConsole});
      }
      if (o.fault) {
        requeue(
            t, "device-fault", o.fault_detail,
            o.untouched ? std::string(source::kRunner) : source::Watchdog(opt.device, o.injected));
        if (opt.ui)
          opt.ui->Event(fmt::format("{} {}: {} (re-queued)", training ? "training trial" : "trial",
                                    screen.index, o.fault_detail));
        queue.push_back(t);
        if (untouched_in_a_row >= opt.max_untouched_trials) {
          return abort({.detail = fmt::format(
                            "{} trials in a row touched nothing: the rig's sample poses are "
                            "probably wrong (hapticlab rig show / rig calibrate)",
                            untouched_in_a_row),
                        .established_by = source::kRunner});
        }
        continue;
      }
      // The ratings commit only with every trajectory stream of this attempt whole.
      try {
        database.CompleteTrial(t.id, o.ratings, writer.TakeReports(t.id));
        trajectory_faults = 0;
      } catch (const db::TrajectoryIncomplete& e) {
        requeue(t, "trajectory-fault", WithoutFolder(database, e.what()), source::kDatabase);
        if (opt.ui)
          opt.ui->Event(fmt::format("{} {}: trajectories not stored (re-queued)",
                                    training ? "training trial" : "trial", screen.index));
        if (++trajectory_faults >= kMaxTrajectoryFaults)
          throw std::runtime_error(
              fmt::format("{} trials in a row could not store their trajectories (a full disk "
                          "or a database that cannot be written); last: {}",
                          trajectory_faults, e.what()));
        queue.push_back(t);
        continue;
      }
      ++sum.completed;
      done.insert(t.id);
      (training ? training_done : rated_done) += 1;
      last_material = t.material;
      // The plan's 1-based number, as `study plan`, events.csv and the exports number it.
      Log(opt, fmt::format("{} trial {}/{} ({} {} {}) done; {} of {} completed", part.code,
                           t.plan_index + 1, sum.planned, t.phase, t.material,
                           t.method.empty() ? t.comparison : t.method, sum.completed, sum.planned));
    }
  }
  // Adaptive phases (staircase, QUEST+): trials chosen one by one from the answers so far.
  const auto adaptive = internal::RunAdaptivePhases(database, session, p, lab.models, part.seed,
                                                    opt, *rig, &writer, &sum.executed);
  sum.planned += adaptive.added;
  sum.completed += adaptive.completed;
  sum.faults += adaptive.faults;
  sum.simulated_s += adaptive.stimulus_s;
  if (adaptive.aborted)
    return finish("aborted");  // RunAdaptivePhases logged it and ended the session
  database.EndSession(session, "completed");
  return finish("completed");
}

}  // namespace

}  // namespace hapticlab::runner::internal
