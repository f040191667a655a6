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
#include "participant.hpp"
#include "trial.hpp"

namespace hapticlab::runner::internal {
namespace {

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
    db::WriteTransaction tx(database);
    database.LogEvent(
        {.session_id = session,
         .kind = db::EventKind::kStopped,
         .detail = "the session stopped on an error: " + WithoutFolder(database, why) +
                   "; completed trials are recorded; fix the cause, then "
                   "'hapticlab study resume'",
         .established_by = source::kRunner});
    database.EndSession(session, db::SessionStatus::kFailed);
    tx.Commit();
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

// The session's remaining planned trials in plan order, phase by phase, faulted ones
// re-queued at their phase's end; breaks, stops and aborts; then the adaptive phases.
class SessionQueue {
 public:
  SessionQueue(db::Database& database, const Lab& lab, std::int64_t session,
               const db::Participant& part, const RunOptions& opt, Rig& rig)
      : database_(database),
        lab_(lab),
        p_(*lab.protocol),
        session_(session),
        part_(part),
        opt_(opt),
        rig_(rig),
        writer_(database.path()) {}
  RunSummary Run();

 private:
  RunSummary Finish(db::SessionStatus status);
  RunSummary Abort(db::Event why);
  void CountTrials();
  std::optional<RunSummary> RunPlannedPhase(protocols::PhaseKind phase);
  std::size_t Pick(const std::vector<db::Trial>& queue, protocols::PhaseKind phase);
  std::optional<RunSummary> StopRequestedBefore(const db::Trial& t);
  TrialScreen Screen(const db::Trial& t, const TrialStimuli& stimuli) const;
  std::optional<RunSummary> BreakAndPlacement(const db::Trial& t, const TrialScreen& screen);
  void Requeue(db::Trial& t, db::EventKind kind, const std::string& cause, const std::string& by);
  std::optional<RunSummary> AfterTrial(db::Trial& t, const Outcome& o, const TrialScreen& screen,
                                       std::vector<db::Trial>* queue);

  static constexpr int kMaxTrajectoryFaults = 3;  // in a row: the disk or the database
  db::Database& database_;
  const Lab& lab_;
  const protocols::Protocol& p_;
  std::int64_t session_;
  const db::Participant& part_;
  const RunOptions& opt_;
  Rig& rig_;
  std::unique_ptr<Participant> participant_;
  db::TrajectoryWriter writer_;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  RunSummary sum_;
  std::vector<db::Trial> trials_;
  std::string last_material_;
  // The screens count rated trials of the planned phases (training apart), 1-based.
  int rated_total_ = 0, rated_done_ = 0, training_total_ = 0, training_done_ = 0;
  int trajectory_faults_ = 0, untouched_in_a_row_ = 0;
  std::set<std::int64_t> break_before_;  // trials the plan puts a break before
  std::set<std::int64_t> done_;          // trials completed (before a resume or now)
  std::optional<std::int64_t> trial_under_way_;
};

}  // namespace

RunSummary ExecuteSession(db::Database& database, const Lab& lab, std::int64_t session,
                          const db::Participant& part, const RunOptions& opt, Rig& rig) {
  try {
    return SessionQueue(database, lab, session, part, opt, rig).Run();
  } catch (const std::exception& e) {
    MarkFailed(database, session, e.what(), opt);
    throw;
  }
}

namespace {

// Every way a session ends goes through Finish; every abort through Abort (the reason logged
// as an event of the session, the session closed as aborted).
RunSummary SessionQueue::Finish(db::SessionStatus status) {
  sum_.status = status;
  sum_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  return sum_;
}

RunSummary SessionQueue::Abort(db::Event why) {
  why.session_id = session_;
  database_.LogEvent(why);
  database_.EndSession(session_, db::SessionStatus::kAborted);
  return Finish(db::SessionStatus::kAborted);
}

void SessionQueue::CountTrials() {
  trials_ = database_.Trials(session_);
  sum_.planned = static_cast<int>(trials_.size());
  for (const auto& t : trials_) {
    const bool completed = t.status == db::TrialStatus::kCompleted;
    if (completed) {
      ++sum_.completed;
      last_material_ = t.material;  // plan order: the last completed trial precedes the next
      done_.insert(t.id);
    }
    (IsTraining(t.phase) ? training_total_ : rated_total_) += 1;
    if (completed) (IsTraining(t.phase) ? training_done_ : rated_done_) += 1;
  }
  for (const auto& e : database_.Events(session_))
    if (e.kind == db::EventKind::kBreakPlanned && e.trial_id) break_before_.insert(*e.trial_id);
}

RunSummary SessionQueue::Run() {
  sum_.session_id = session_;
  sum_.participant = part_.code;
  HL_REQUIRE(rig_.device != nullptr, "RunOptions::rig has no device");
  // Who holds the stylus and answers: the one seam to simulation (participant.hpp).
  participant_ = MakeParticipant(rig_, lab_, opt_, part_.seed);
  if (opt_.rig)  // a rig the caller opened (the one a simulated session opens is not logged)
    database_.LogEvent({.session_id = session_,
                        .kind = db::EventKind::kDevice,
                        .detail = rig_.description,
                        .established_by = source::Device(opt_.device)});
  // Masking noise on the headphones for the whole session (ch. IV.5.1, V.2.1).
  struct Noise {
    devices::MaskingNoise* n;
    ~Noise() {
      if (n) n->SetNoiseLevel(0);
    }
  } noise{p_.masking_noise ? rig_.noise : nullptr};
  if (noise.n) noise.n->SetNoiseLevel(rig_.noise_rms_fs);
  CountTrials();
  // The experimenter's actions in the console (pause, resume, abort asked / cancelled, a
  // break ended early) become session events, tied to the trial under way.
  struct UiEvents {
    SessionUi* ui;
    ~UiEvents() {
      if (ui) ui->log_event = nullptr;
    }
  } ui_events{opt_.ui};
  if (opt_.ui)
    opt_.ui->log_event = [this](db::EventKind kind, const std::string& detail) {
      database_.LogEvent({.session_id = session_,
                          .trial_id = trial_under_way_,
                          .kind = kind,
                          .detail = detail,
                          .established_by = source::kConsole});
    };
  using protocols::PhaseKind;
  for (const PhaseKind phase : {PhaseKind::kTraining, PhaseKind::kReference, PhaseKind::kMain})
    if (auto stopped = RunPlannedPhase(phase)) return *stopped;
  // Adaptive phases (staircase, QUEST+): trials chosen one by one from the answers so far.
  const TrialContext c{rig_, *participant_, opt_, &writer_, database_, session_};
  const auto adaptive = internal::RunAdaptivePhases(p_, lab_.models, part_.seed, c, &sum_.executed);
  sum_.planned += adaptive.added;
  sum_.completed += adaptive.completed;
  sum_.faults += adaptive.faults;
  sum_.simulated_s += adaptive.stimulus_s;
  if (adaptive.aborted)
    return Finish(db::SessionStatus::kAborted);  // RunAdaptivePhases ended the session
  database_.EndSession(session_, db::SessionStatus::kCompleted);
  return Finish(db::SessionStatus::kCompleted);
}

std::optional<RunSummary> SessionQueue::RunPlannedPhase(protocols::PhaseKind phase) {
  std::vector<db::Trial> queue;
  for (const auto& t : trials_)
    if (t.phase == phase && t.status != db::TrialStatus::kCompleted &&
        t.status != db::TrialStatus::kFaulted)
      queue.push_back(t);
  for (const auto& t : trials_)  // faulted before a crash: retried at the phase's end
    if (t.phase == phase && t.status == db::TrialStatus::kFaulted) queue.push_back(t);
  while (!queue.empty()) {
    const std::size_t pick = Pick(queue, phase);
    db::Trial t = queue[pick];
    queue.erase(queue.begin() + static_cast<std::ptrdiff_t>(pick));
    if (auto stopped = StopRequestedBefore(t)) return stopped;
    // The console shows this trial as the next one from now on: through a break and while
    // its samples are placed.
    const TrialStimuli stimuli = ParseStimuli(t);
    const TrialScreen screen = Screen(t, stimuli);
    if (opt_.ui) opt_.ui->Upcoming(screen);
    if (auto stopped = BreakAndPlacement(t, screen)) return stopped;
    database_.StartTrial(t.id);
    ++t.attempts;
    ++sum_.executed;
    trial_under_way_ = t.id;
    const TrialContext c{rig_, *participant_, opt_, &writer_, database_, session_};
    const Outcome o = ExecuteTrial(lab_, t, stimuli, part_.seed, c, screen);
    if (auto stopped = AfterTrial(t, o, screen, &queue)) return stopped;
  }
  return std::nullopt;
}

// The next trial of the queue: its head, or with the no-immediate-repeat constraint the
// first trial of another material than the last one (re-queued trials), when one remains.
std::size_t SessionQueue::Pick(const std::vector<db::Trial>& queue, protocols::PhaseKind phase) {
  if (!p_.randomization.no_immediate_repeat || queue[0].material != last_material_ ||
      phase == protocols::PhaseKind::kTraining)
    return 0;
  for (std::size_t i = 1; i < queue.size(); ++i)
    if (queue[i].material != last_material_) return i;
  if (queue.size() > 1)
    database_.LogEvent({.session_id = session_,
                        .trial_id = queue[0].id,
                        .kind = db::EventKind::kConstraintRelaxed,
                        .detail = "only trials of the same material remain in the phase",
                        .established_by = source::kRunner});
  return 0;
}

// A stop asked for before trial `t` (a signal, --stop-after): the session ends aborted.
std::optional<RunSummary> SessionQueue::StopRequestedBefore(const db::Trial& t) {
  if (const int sig = StopRequested()) {
    return Abort({.trial_id = t.id,
                  .kind = db::EventKind::kInterrupted,
                  .detail = fmt::format("stopped by signal {} ({}) before this trial; 'study "
                                        "resume' continues with it",
                                        sig,
                                        sig == SIGINT    ? "SIGINT"
                                        : sig == SIGTERM ? "SIGTERM"
                                                         : "signal"),
                  .established_by = source::kSignal});
  }
  if (opt_.stop_after_trials >= 0 && sum_.executed >= opt_.stop_after_trials)
    return Abort({.kind = db::EventKind::kAbort,
                  .detail = "stopped after the requested number of trials",
                  .established_by = source::CommandLine("--stop-after")});
  return std::nullopt;
}

TrialScreen SessionQueue::Screen(const db::Trial& t, const TrialStimuli& stimuli) const {
  const bool training = IsTraining(t.phase);
  auto screen = ScreenOf(p_, t, stimuli, training ? training_done_ + 1 : rated_done_ + 1,
                         training ? training_total_ : rated_total_);
  screen.training = training;
  screen.break_s = p_.break_duration_s / participant_->PlaybackSpeed();  // as Break takes it
  screen.rated_done = rated_done_;
  screen.rated_total = rated_total_;
  screen.training_done = training_done_;
  screen.training_total = training_total_;
  screen.plan_total = sum_.planned;
  screen.break_before = break_before_.count(t.id) && !training;
  screen.breaks_left = 0;
  for (const auto& b : trials_)
    if (break_before_.count(b.id) && !IsTraining(b.phase) && !done_.count(b.id) && b.id != t.id)
      ++screen.breaks_left;
  return screen;
}

// With screens: the planned (or requested) break before trial `t`, then the experimenter's
// confirmation that its real samples are in place. An abort there ends the session.
std::optional<RunSummary> SessionQueue::BreakAndPlacement(const db::Trial& t,
                                                          const TrialScreen& screen) {
  if (!opt_.ui) return std::nullopt;
  const bool requested = opt_.ui->TakeBreakNow();
  if (requested || (break_before_.count(t.id) && !IsTraining(t.phase))) {
    // A simulated session played faster (--ui-speed) shortens its breaks alike.
    const double speed = participant_->PlaybackSpeed();
    const double break_s = p_.break_duration_s / speed;
    database_.LogEvent({.session_id = session_,
                        .trial_id = t.id,
                        .kind = db::EventKind::kBreak,
                        .detail = fmt::format(
                            "{:.0f} s break ({}{})", break_s,
                            requested ? "requested by the experimenter" : "planned",
                            speed != 1.0 ? fmt::format("; played {:g} times faster", speed) : ""),
                        .established_by = requested ? source::kConsole : source::kPlan});
    trial_under_way_ = t.id;
    if (!opt_.ui->Break(break_s)) {
      if (auto stopped = StopRequestedBefore(t)) return stopped;  // a signal ended the break
      return Abort({.trial_id = t.id,
                    .kind = db::EventKind::kAbort,
                    .detail = "the experimenter aborted during a break",
                    .established_by = source::kConsole});
    }
  }
  if (screen.real_sample) {
    // No trial with a real sample starts before the experimenter confirms its samples.
    trial_under_way_ = t.id;
    const auto how = opt_.ui->ConfirmPlacement(screen);
    if (!how) {
      if (auto stopped = StopRequestedBefore(t)) return stopped;  // a signal ended the wait
      return Abort({.trial_id = t.id,
                    .kind = db::EventKind::kAbort,
                    .detail = "the experimenter aborted while placing the samples; 'study "
                              "resume' continues with this trial",
                    .established_by = source::kConsole});
    }
    database_.LogEvent(
        {.session_id = session_,
         .trial_id = t.id,
         .kind = db::EventKind::kSamplesPlaced,
         .detail = fmt::format("trial {}: {}; {}", screen.plan_number, screen.placement, *how),
         .established_by = how->starts_with("not confirmed") ? source::kRunner : source::kConsole});
  }
  return std::nullopt;
}

// A faulted attempt of trial `t`: its cause as an event (established by `by`), then the
// runner's re-queue as an 'attempt-faulted' event (counted by 'study status') and a line on
// the log even without progress lines. The caller re-queues `t`.
void SessionQueue::Requeue(db::Trial& t, db::EventKind kind, const std::string& cause,
                           const std::string& by) {
  ++sum_.faults;
  database_.SetTrialStatus(t.id, db::TrialStatus::kFaulted);
  database_.LogEvent({.session_id = session_,
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
                  t.plan_index + 1, NameOf(kPhaseKindNames, t.phase), t.attempts, why,
                  NameOf(kPhaseKindNames, t.phase));
  database_.LogEvent({.session_id = session_,
                      .trial_id = t.id,
                      .kind = db::EventKind::kAttemptFaulted,
                      .detail = line,
                      .established_by = source::kRunner});
  Warn(opt_, part_.code + ": " + line);
  t.status = db::TrialStatus::kFaulted;
}

// What trial `t`'s outcome does to the session: an abort ends it; a fault re-queues the
// trial (too many untouched in a row abort); otherwise the ratings commit with every
// trajectory stream of the attempt whole (else the trial is re-queued).
std::optional<RunSummary> SessionQueue::AfterTrial(db::Trial& t, const Outcome& o,
                                                   const TrialScreen& screen,
                                                   std::vector<db::Trial>* queue) {
  const bool training = IsTraining(t.phase);
  const char* what = training ? "training trial" : "trial";
  sum_.simulated_s += o.stimulus_s;
  untouched_in_a_row_ = o.untouched ? untouched_in_a_row_ + 1 : 0;
  if (o.aborted)
    return Abort({.trial_id = t.id,
                  .kind = db::EventKind::kAbort,
                  .detail = "the experimenter aborted in the console; 'study resume' continues "
                            "with this trial",
                  .established_by = source::kConsole});
  if (o.fault) {
    Requeue(t, db::EventKind::kDeviceFault, o.fault_detail,
            o.untouched ? std::string(source::kRunner) : source::Watchdog(opt_.device, o.injected));
    if (opt_.ui)
      opt_.ui->Event(fmt::format("{} {}: {} (re-queued)", what, screen.index, o.fault_detail));
    queue->push_back(t);
    if (untouched_in_a_row_ >= opt_.max_untouched_trials)
      return Abort({.kind = db::EventKind::kAbort,
                    .detail = fmt::format(
                        "{} trials in a row touched nothing: the rig's sample poses are probably "
                        "wrong (hapticlab rig show / rig calibrate)",
                        untouched_in_a_row_),
                    .established_by = source::kRunner});
    return std::nullopt;
  }
  try {
    database_.CompleteTrial(t.id, o.ratings, writer_.TakeReports(t.id));
    trajectory_faults_ = 0;
  } catch (const db::TrajectoryIncomplete& e) {
    Requeue(t, db::EventKind::kTrajectoryFault, WithoutFolder(database_, e.what()),
            source::kDatabase);
    if (opt_.ui)
      opt_.ui->Event(fmt::format("{} {}: trajectories not stored (re-queued)", what, screen.index));
    if (++trajectory_faults_ >= kMaxTrajectoryFaults)
      throw std::runtime_error(
          fmt::format("{} trials in a row could not store their trajectories (a full disk "
                      "or a database that cannot be written); last: {}",
                      trajectory_faults_, e.what()));
    queue->push_back(t);
    return std::nullopt;
  }
  ++sum_.completed;
  done_.insert(t.id);
  (training ? training_done_ : rated_done_) += 1;
  last_material_ = t.material;
  // The plan's 1-based number, as `study plan`, events.csv and the exports number it.
  Log(opt_,
      fmt::format("{} trial {}/{} ({} {} {}) done; {} of {} completed", part_.code,
                  t.plan_index + 1, sum_.planned, NameOf(kPhaseKindNames, t.phase), t.material,
                  t.method.empty() ? t.comparison : t.method, sum_.completed, sum_.planned));
  return std::nullopt;
}

}  // namespace

}  // namespace hapticlab::runner::internal
