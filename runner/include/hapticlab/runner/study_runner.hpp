#pragma once
/// @file Runs a study protocol for one participant and records everything: the session
/// state machine (consent -> training -> reference -> main, with breaks, abort and resume),
/// trial execution, ratings committed one transaction per trial, trajectories through the
/// writer thread, events and provenance.
///
/// One trial path: every trial side, simulated or on hardware, runs the method's
/// HybridRenderer inside RtEngine over the rig's HapticDevice and Actuator, with the watchdog
/// and the trajectory writer. A simulated rig (sim::SimRig: a simulated hand holding a
/// simulated device) differs only in its clock (virtual, stepped as fast as the ticks run)
/// and in who rates (the simulated observer, from what the hand felt).
///
/// Guarantees: the plan is stored before the first trial; a trial's ratings and completion
/// marker commit together; `ResumeStudy` continues with exactly the trials not completed
/// (none twice, none skipped); a faulted trial is re-queued at the end of its phase in a
/// position that keeps the no-immediate-repeat constraint when any such position exists.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/devices/device.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/sim/sim_device.hpp"

namespace hapticlab::runner {

/// What to record of each trial's interactions.
enum class RecordMode { kNone, kForce, kAll };
/// Their names (`--record`), in the order --help lists them.
inline constexpr EnumTable<RecordMode, 3> kRecordModeNames{
    {{RecordMode::kAll, "all"}, {RecordMode::kForce, "force"}, {RecordMode::kNone, "none"}}};

/// What a user interface shows of a trial (hapticlab study run --ui).
struct TrialScreen {
  /// 1-based number of this trial among the rated trials of the planned phases, and how
  /// many there are; a training trial (`training`) counts among the training trials instead.
  int index = 0, total = 0;
  /// The trial's number in the participant's plan (1-based) and the plan's length: the one
  /// number the run's log, `study plan`, events.csv and the exports give this trial.
  int plan_number = 0, plan_total = 0;
  bool training = false;
  int rated_done = 0, rated_total = 0;  ///< rated trials completed / planned (console progress)
  int training_done = 0, training_total = 0;  ///< training trials completed / planned
  std::string phase, left, right, method,
      placement;  ///< placement: what the experimenter puts where
  std::vector<std::string> criteria;
  double scale_min = 0, scale_max = 100;
  std::string scale_low = "very different", scale_high = "identical";
  /// Adaptive trials (staircase, QUEST+): the question and the answers offered, e.g.
  /// {"1", "2"} for the intervals of a 2AFC trial or {"yes", "no"}.
  std::string question;
  std::vector<std::string> answers;
  /// The left side or the right side presents a real sample: the experimenter places it
  /// (SessionUi::ConfirmPlacement) before the trial starts.
  bool real_sample = false;
  /// For the console's time estimate: the stimulus time per side [s], the sides per trial
  /// (1 for training), whether the plan puts a break before this trial, the planned breaks
  /// after it and their duration [s].
  double stimulus_s = 0;
  int sides = 2;
  bool break_before = false;
  int breaks_left = 0;
  double break_s = 0;
};

/// One frame of live data while a side runs (SessionUi::Live), read on the runner's thread:
/// the newest row of the side's recorded streams as the trajectory writer took it from the
/// engine's queue (TrajectoryStream::Latest; the force and vibration ticks are untouched) and
/// the engine's counters and timing so far (RtEngine::Stats, atomics and histograms).
struct LiveFrame {
  int plan_number = 0;          ///< the trial's 1-based plan number
  int side = 0;                 ///< the screen side: 0 left (A), 1 right (B)
  std::string stimulus;         ///< "real:Denim", "virtual:Denim"
  bool final = false;           ///< the side has ended: `engine` holds its totals
  bool force_recorded = false;  ///< `force` holds a recorded row (none with --record none)
  double force_t_s = 0;         ///< the row's time stamp on the side's clock [s]
  std::array<float, db::kForceChannelCount> force{};  ///< in db::ForceChannel order
  bool vibration_recorded = false;                    ///< `vibration_mps2` holds a recorded sample
  double vibration_t_s = 0;
  float vibration_mps2 = 0;  ///< the vibration command [m/s^2]
  EngineStats engine;
};

/// What a console shows when it asks the experimenter to confirm a participant's consent
/// (SessionUi::ConfirmConsent): the protocol's `[consent]` document and version.
struct ConsentRequest {
  std::string study, participant, document, version;
};

/// A person's rating `v` as stored: on the scale's step (the largest power of ten giving
/// [lo, hi] at least 100 steps: 1 on 0..100, 0.01 on 0..1), clamped to the scale. A rating
/// from the window (a float mouse position) or a rating box is stored as that scale value,
/// e.g. 80, not 80.000001192092896.
double ScaleValue(double v, double lo, double hi);

/// Hooks a user interface into a session: the runner calls it from its own (main) thread.
/// A GLFW implementation is runner/session_ui.hpp; tests script it.
class SessionUi {
 public:
  virtual ~SessionUi() = default;
  /// One frame while the participant explores side 0 (left) or 1 (right): the stylus [m,
  /// in that sample's frame] and the stimulus time left. false: the experimenter
  /// aborted.
  virtual bool Stimulus(const TrialScreen& t, int side, const Eigen::Vector3d& stylus_m,
                        double remaining_s) = 0;
  /// Blocks until the participant confirms a rating per criterion (in the protocol's scale),
  /// or the experimenter aborts (nullopt).
  virtual std::optional<std::vector<double>> Rate(const TrialScreen& t) = 0;
  /// Blocks until the participant picks one of `t.answers` (adaptive trials); returns its
  /// index, or nullopt when the experimenter aborted. A UI without answer keys keeps this
  /// default and cannot run adaptive phases (they abort at their first trial).
  virtual std::optional<int> Choose(const TrialScreen& t) {
    (void)t;
    return std::nullopt;
  }
  /// Asked once before the session's first trial when a person takes part and consent was
  /// not confirmed on the command line: blocks until the experimenter confirms that the
  /// participant consented to `r.document` version `r.version`, and returns the
  /// experimenter's pseudonymous code; nullopt when it was not confirmed. The runner records
  /// it with RecordConsent (via "console"). A UI that cannot ask keeps this default: the
  /// session then needs RunOptions::consent_confirmed_by.
  virtual std::optional<std::string> ConfirmConsent(const ConsentRequest& r) {
    (void)r;
    return std::nullopt;
  }
  /// Blocks through a break with a countdown. false: aborted.
  virtual bool Break(double seconds) = 0;
  /// A line for the console's log (faults, resume, ...).
  virtual void Event(const std::string&) {}
  /// Polled before each trial: the experimenter asked for a break (cleared by reading).
  virtual bool TakeBreakNow() { return false; }
  /// Live data of the side being explored, before each Stimulus frame and once more (final)
  /// when the side has ended.
  virtual void Live(const LiveFrame& f) { (void)f; }
  /// The trial that comes next, as soon as it is known: right after the previous trial
  /// (rated, faulted or skipped), before a break or the placement of samples.
  virtual void Upcoming(const TrialScreen& next) { (void)next; }
  /// Blocks until the experimenter confirms that the samples of `t` (t.real_sample) are in
  /// place; returns who confirmed it and how (e.g. "confirmed by the experimenter: console
  /// button"), or nullopt when the
  /// experimenter aborted. The runner logs the confirmation as a 'samples-placed' event and
  /// starts no trial with a real sample before it. An interface without a placement step (a
  /// test's scripted rater) keeps this default, which says so in the event.
  virtual std::optional<std::string> ConfirmPlacement(const TrialScreen& t) {
    (void)t;
    return std::string("not confirmed: this interface has no placement step (scripted)");
  }
  /// Set by the runner while a session runs: the UI records the experimenter's actions
  /// (pause, resume, abort requested / cancelled, break ended early) as session events.
  std::function<void(db::EventKind kind, const std::string& detail)> log_event;
};

/// What one trial side did in the engine (RunOptions::on_side; tests and diagnostics).
struct SideReport {
  int plan_index = 0, side = 0, attempt = 0;
  std::string stimulus;  ///< "real:Denim", "virtual:Denim"
  EngineStats engine;
  std::uint64_t hand_ticks = 0;     ///< simulated rig: ticks the hand was stepped
  std::uint64_t contact_ticks = 0;  ///< ticks the renderer found the stylus inside the surface
};

/// What the simulated hand felt in one rated trial, as the observer's feature distance per
/// criterion (protocol order) before its rating (RunOptions::on_felt; `study power`), and the
/// features of the two sides themselves (`study calibrate` recomputes distances when it fits
/// the observer's perceptual scales).
struct FeltTrial {
  int plan_index = 0;
  PhaseKind phase = PhaseKind::kMain;
  std::string material, comparison, method;
  int repetition = 0;
  std::vector<double> distances;
  std::array<sim::Features, 2> felt{};
};

/// Who rates a session's trials: the simulated observer, or a person in the participant
/// window, by mouse or on a rating box. The database records it by name (the session's
/// `rater`, each rating's `source`): "simulated", "window", "rating-box:VID:PID".
enum class RaterKind { kSimulated, kWindow, kRatingBox };
struct Rater {
  RaterKind kind = RaterKind::kSimulated;
  std::string box;  ///< kRatingBox: the box's "VID:PID" (hex)
  /// The name the database records.
  std::string Name() const;
  bool operator==(const Rater&) const = default;
};
/// The rater a recorded name gives. @throws InputError at (file, 0, field) for a name that
/// is none of the above
Rater ParseRater(const std::string& name, const std::string& file, const std::string& field);
/// Who rates a session run with screens (`ui`) or not, on the rating box "VID:PID" (empty: by
/// mouse in the window): the simulated observer without screens.
Rater RaterOf(bool ui, const std::string& rating_box);

struct RunOptions {
  std::string db_path;
  std::string participant;     ///< pseudonymous code, e.g. "P07"
  int participant_index = -1;  ///< plan index; -1: the next free index in the study
  /// The device back-end's name (runner/open_rig.hpp; recorded). Without `rig`, a simulated
  /// back-end's rig is opened for the session (its generic device seeded from the participant).
  std::string device = DefaultBackendName();
  RecordMode record = RecordMode::kAll;
  int stop_after_trials = -1;  ///< abort the session after this many trials (tests; -1: run all)
  double fault_rate = 0;       ///< sim: probability that a trial's link drops out for 50 ms (tests)
  std::function<void(const std::string&)> log;  ///< progress lines (may be empty)
  /// Participant and console windows: ratings come from the participant; the stimulus is
  /// shown (sim: the simulated strokes, played in real time). Borrowed; may be null.
  SessionUi* ui = nullptr;
  double ui_playback_speed = 1.0;  ///< simulated rig with a UI: virtual time runs this much faster
  Rig* rig = nullptr;              ///< the opened rig (borrowed); required for a hardware back-end
  std::function<void(const SideReport&)> on_side;  ///< after every trial side (may be empty)
  std::function<void(const FeltTrial&)>
      on_felt;  ///< simulated rig: before every rating (may be empty)
  /// Abort the session after this many trials in a row where a side touched nothing (the
  /// rig's sample pose is probably wrong).
  int max_untouched_trials = 3;
  // The session's mode besides `device` and `ui` (recorded; resume continues in it).
  ActuatorKind actuator = ActuatorKind::kNone;  ///< the vibrotactile actuator
  /// With a UI: the rating box ("VID:PID") the participant rates on; empty: the window.
  std::string rating_box;
  /// Resume: continue in this mode although it differs from the recorded one (logged as a
  /// 'mode-change' event); without it a different mode is refused.
  bool change_mode = false;
  /// What the loop threads ask for on the real clock (spin, SCHED_FIFO, mlockall, CPU);
  /// outcomes are stored per trial side (db/timing.hpp). Ignored on a virtual clock.
  RtThreadOptions rt;
  /// Lines a person must see even without progress lines: each faulted attempt (trial plan
  /// number, cause, re-queued) and why a session stopped on an error (may be empty).
  std::function<void(const std::string&)> warn;
  /// The experimenter's pseudonymous code confirming, before the session, that the
  /// participant consented to the protocol's `[consent]` document (`--consent-confirmed-by`).
  /// Needed when a person takes part (PersonTakesPart) unless the UI asks
  /// (SessionUi::ConfirmConsent); refused for a simulated session. runner/audit.hpp.
  std::string consent_confirmed_by;
  /// The site recording the session (`--site`; schema v10): a short pseudonymous code
  /// (db::SiteCodeProblem); "L0" is the local default.
  std::string site = "L0";
  /// Simulated observer: rating points added to every rating of the session, a site effect
  /// (`--site-offset`, tests and replication examples; recorded in the provenance and kept by
  /// `study resume`). Refused with a person rating.
  double site_offset = 0;
  /// The preregistered plan the session runs under (`study run --plan`; replication/plan.hpp):
  /// its hash and the site that imported it, recorded in the provenance as "plan_sha256" and
  /// "plan_site"; empty: none.
  std::string plan_sha256, plan_site;
  /// The protocol keys that differ from the plan's (a protocol given instead of the plan's,
  /// protocols::CanonicalDifferences), recorded as "plan_protocol_changes": each session keeps
  /// its own deviations through `db merge`, which keeps one protocol text per study.
  std::vector<std::string> plan_protocol_changes;
  /// Material models replacing the protocol's (a replicating site's own models, `study import
  /// --substitute`): material id -> model file. Recorded in the provenance
  /// ("substituted_models": file relative to the database's folder, SHA-256); `study resume`
  /// loads them again from there.
  std::map<std::string, std::string> model_files;
};

/// A session's mode: what `study run` recorded and `study resume` continues in.
struct SessionMode {
  std::string device = DefaultBackendName();  ///< back-end
  /// None: "unrecorded" (a session before schema v5; it matches any actuator on resume).
  std::optional<ActuatorKind> actuator = ActuatorKind::kNone;
  bool screens = false;  ///< --ui
  Rater rater;           ///< the simulated observer, or the participant's input device
  std::string study;     ///< the study's name (RecordedMode fills it in; not part of the mode)
  std::string Describe()
      const;  ///< e.g. "device sim, actuator none, screens off, ratings simulated"
};

/// Resuming in `now` a session recorded in `recorded`: true when the mode changes (allowed
/// only with `change_mode`). A field recorded as "unrecorded" (before schema v5) matches any.
/// @throws InputError naming both modes when they differ and `change_mode` is false
bool CheckResumeMode(const SessionMode& recorded, const SessionMode& now, bool change_mode,
                     const std::string& db_path, const std::string& participant);

/// The mode a RunOptions runs in.
SessionMode ModeOf(const RunOptions& options);

/// The recorded mode of a participant's last session (for `study resume` to default to).
/// @throws InputError when the database or the participant does not exist, the session is
/// completed (nothing to resume), or the session
/// records an actuator or rater this build does not know (field session.actuator/rater)
SessionMode RecordedMode(const std::string& db_path, const std::string& participant);

/// Every check `RunStudy` makes before it writes anything, for `study validate`: adaptive
/// phases runnable on the device, the profiles file (looked up relative to the protocol
/// file's folder) present and naming every material's profile, every model file present and
/// loadable, and for a session with a person (`ui`, or a hardware device) the protocol's
/// `[consent]` document. @throws InputError listing every problem (file, line, key, path)
void CheckRunnable(const protocols::Protocol& protocol,
                   const std::string& device = DefaultBackendName(), bool ui = false);

/// The plan index of participant `code` of study `study` in the database (`study plan
/// --participant CODE --db DB`). @throws InputError when there is no such participant
int ParticipantIndex(const std::string& db_path, const std::string& study, const std::string& code);

/// Asks a running session to stop at the next trial boundary: it ends 'aborted' with an
/// 'interrupted' event and checkpoints the database (async-signal-safe: for SIGINT/SIGTERM
/// handlers). `study resume` continues it.
void RequestStop(int signal_number) noexcept;
/// The signal that requested a stop (0: none).
int StopRequested() noexcept;

struct RunSummary {
  std::int64_t session_id = 0;
  std::string participant;
  db::SessionStatus status = db::SessionStatus::kRunning;  ///< kCompleted or kAborted when returned
  int planned = 0, completed = 0, executed = 0, faults = 0;
  double simulated_s = 0;  ///< stimulus time rendered (sim)
  double wall_s = 0;
};

/// Starts a new participant on `protocol` (creating the study in the database if needed).
/// @throws hapticlab::InputError on bad input (participant exists, protocol changed, ...)
RunSummary RunStudy(const protocols::Protocol& protocol, const RunOptions& options);

/// Continues the participant's session where it stopped (crash or abort).
RunSummary ResumeStudy(const RunOptions& options);

struct ParticipantStatus {
  std::string code;
  int planned = 0, completed = 0;
  int faulted = 0;     ///< faulted attempts (each re-queued; 'attempt-faulted' events)
  int duplicates = 0;  ///< planned trials completed more than once (must be 0)
  /// The last session's status; none: a code reserved by `participant new` (no session yet).
  std::optional<db::SessionStatus> session_status;
};
/// Progress of every participant (or one) in the database.
std::vector<ParticipantStatus> StudyStatus(const std::string& db_path,
                                           const std::string& participant = "");

}  // namespace hapticlab::runner
