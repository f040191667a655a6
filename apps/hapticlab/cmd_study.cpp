// hapticlab study: validate, plan, run, resume and inspect study protocols.

#include <fmt/core.h>

#include <array>
#include <csignal>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/factory.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/plan_json.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/runner_ui/session_ui.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "rig_timing.hpp"
#include "study_plan.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;

struct RunArgs {
  std::string protocol, db, participant, device = runner::DefaultBackendName();
  runner::RecordMode record = runner::RecordMode::kAll;
  int index = -1, stop_after = -1;
  double fault_rate = 0;
  bool ui = false, json = false, quiet = false, change_mode = false;
  // Hardware and screens.
  std::string firmware, audio_device, rig_file, rating_box, rating_layout;
  runner::ActuatorKind actuator = runner::ActuatorKind::kNone;
  double noise_rms = 0.1, ui_speed = 1.0, full_scale_mps2 = 50;
  bool fullscreen = false;
  runner::RtThreadOptions rt;
  std::string consent_by;   ///< --consent-confirmed-by: the experimenter's code
  std::string site = "L0";  ///< --site (study run)
  double site_offset = 0;   ///< --site-offset (study run, simulated observer)
  /// study resume: the recorded mode (SessionMode::Describe), for a mode that cannot start
  std::string recorded_mode;
  std::string plan;  ///< study run --plan: a plan or imported site directory
};

// Opens the hardware and the windows a run asks for and keeps them alive for the session.
class Rig {
 public:
  Rig(const RunArgs& a, const std::string& study, const std::string& participant,
      runner::RunOptions* o) {
    WithFlags({{"device", "--device"},
               {"firmware", "--firmware"},
               {"actuator", "--actuator"},
               {"rating_box", "--rating-box"},
               {"rating_layout", "--rating-layout"}},
              [&] { Open(a, study, participant, o); });
  }

 private:
  void Open(const RunArgs& a, const std::string& study, const std::string& participant,
            runner::RunOptions* o) {
    o->device = a.device;
    o->actuator = a.actuator;
    o->rating_box = a.rating_box;
    const runner::RigBackend& backend = runner::GetBackend(a.device);
    if (!backend.simulated() && !a.ui) {  // before any device is opened
      Diagnostics d;
      d.Add(kCommandLine, 0, "--ui",
            "a hardware session takes its ratings from the participant window: add --ui");
      if (a.consent_by.empty())
        d.Add(kCommandLine, 0, "--consent-confirmed-by",
              "a person takes part in a hardware session: give the code of the experimenter who "
              "confirmed their consent (e.g. E01), never a name");
      d.ThrowIfAny();
    }
    if (!a.rating_box.empty() && !a.ui)
      throw InputError(kCommandLine, 0, "--rating-box",
                       "the rating box feeds the participant window: add --ui");
    // Frames and calibration: the rig file, or the back-end's built-in rig.
    runner::RigRequest q{.device = a.device,
                         .rig_file = a.rig_file.empty() ? std::optional<runner::RigFile>()
                                                        : runner::LoadRig(a.rig_file),
                         .firmware = a.firmware,
                         .actuator = o->actuator,
                         .audio_device = a.audio_device,
                         .full_scale_mps2 = a.full_scale_mps2,
                         .noise_rms_fs = a.noise_rms,
                         .rating_box = a.rating_box,
                         .rating_layout = a.rating_layout};
    q.progress = [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
    rig_ = runner::OpenRig(q);
    o->rig = rig_.get();
    std::string status = rig_->description;
    if (!a.rating_box.empty()) status += "; rating box " + a.rating_box;
    if (a.ui) {
      runner::ui::WindowOptions wo;
      wo.participant_fullscreen = a.fullscreen;
      try {
        ui_ = std::make_unique<runner::ui::WindowSessionUi>(study, participant, status, wo,
                                                            rig_->rating_input);
      } catch (const std::runtime_error& e) {
        if (a.recorded_mode.empty()) throw;  // study run: the environment (exit 1)
        // study resume in the recorded mode, which cannot start here.
        throw InputError(
            kCommandLine, 0, "--ui",
            fmt::format("{}'s session was recorded in mode [{}], which cannot start here ({}). "
                        "Resume it where a display is, or continue in mode [device {}, "
                        "actuator {}, screens off, ratings simulated] with '--ui=false "
                        "--change-mode' (logged; each rating records its source)",
                        participant, a.recorded_mode, e.what(), a.device,
                        NameOf(runner::kActuatorNames, a.actuator)));
      }
      o->ui = ui_.get();
      o->ui_playback_speed = a.ui_speed;
    }
  }

  std::unique_ptr<runner::Rig> rig_;
  std::unique_ptr<runner::ui::WindowSessionUi> ui_;
};

void PrintSummary(const runner::RunSummary& s, bool json_out) {
  if (json_out) {
    PrintJson(json{{"participant", s.participant},
                   {"session", s.session_id},
                   {"status", std::string(NameOf(db::kSessionStatusNames, s.status))},
                   {"planned", s.planned},
                   {"completed", s.completed},
                   {"executed", s.executed},
                   {"faults", s.faults},
                   {"simulated_s", s.simulated_s},
                   {"wall_s", s.wall_s}});
  } else {
    fmt::print(
        "{}: session {} {} — {}/{} trials completed, {} faults re-queued; {:.0f} s of stimuli in "
        "{:.1f} s\n",
        s.participant, s.session_id, NameOf(db::kSessionStatusNames, s.status), s.completed,
        s.planned, s.faults, s.simulated_s, s.wall_s);
  }
}

// SIGINT and SIGTERM ask the running session to stop at the next trial boundary (it ends
// 'aborted', logs an 'interrupted' event and checkpoints the database); a second signal
// ends the process at once, as the default action would.
extern "C" void OnStopSignal(int sig) {
  if (runner::StopRequested()) {
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  runner::RequestStop(sig);
}

void InstallStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sa.sa_flags =
      SA_RESTART;  // other threads' system calls resume; the flag is polled between trials
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// study run / resume: opens the rig and windows `a` asks for, completes `o` from `a`, runs
// `session` with the stop handlers installed and prints its summary; the exit code.
int RunSession(const RunArgs& a, const std::string& study, runner::RunOptions o,
               const std::function<runner::RunSummary(const runner::RunOptions&)>& session) {
  Rig rig(a, study, a.participant, &o);
  o.db_path = a.db;
  o.participant = a.participant;
  o.record = a.record;
  o.stop_after_trials = a.stop_after;
  o.rt = a.rt;
  o.consent_confirmed_by = a.consent_by;
  if (!a.quiet && !a.json) o.log = StderrLog(false);
  if (!a.json) o.warn = StderrLog(false);  // faulted attempts: also with --quiet
  InstallStopHandlers();
  const auto sum = session(o);
  PrintSummary(sum, a.json);
  if (sum.status != db::SessionStatus::kAborted) return kExitOk;
  if (!a.json) {
    std::fflush(stdout);  // the summary first, then how to continue
    const int sig = runner::StopRequested();
    fmt::print(stderr,
               "{}: stopped before the session's end{}; continue with 'hapticlab study "
               "resume --db {} --participant {}'\n",
               sum.participant,
               sig == SIGINT    ? " by SIGINT (Ctrl-C)"
               : sig == SIGTERM ? " by SIGTERM"
                                : "",
               a.db, sum.participant);
  }
  return kExitStopped;
}

// RunGuarded, with the runner's names for what the user gave ("participant", "db", ...)
// shown as the options that gave them.
void RunStudyGuarded(const std::function<int()>& body) {
  RunGuarded({{"participant", "--participant"},
              {"db", "--db"},
              {"change_mode", "--change-mode"},
              {"consent_confirmed_by", "--consent-confirmed-by"}},
             body);
}

// One registration per subcommand of 'study'.

void RegisterStudyValidate(CLI::App* study) {
  auto path = std::make_shared<std::string>();
  auto device = std::make_shared<std::string>(runner::DefaultBackendName());
  auto ui = std::make_shared<bool>(false);
  auto* cmd = study->add_subcommand(
      "validate",
      "Check a protocol as 'study run' would before it starts: the protocol itself (planned and\n"
      "adaptive phases), the profiles file and every model file (looked up relative to the\n"
      "protocol file's folder), every material's profile. Every problem is listed with file,\n"
      "line and key.");
  cmd->add_option("PROTOCOL", *path, "Study protocol (.toml)")->required();
  cmd->add_option("--device", *device, "Check for this back-end (as 'study run --device')")
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  cmd->add_flag("--ui", *ui,
                "Check for a session rated in the participant window (as 'study run --ui')");
  cmd->callback([=] {
    RunGuarded([&] {
      const auto p = protocols::LoadProtocol(*path);
      stats::CheckAnalyses(p);  // the keywords of [analysis] tests: the stats registry's
      runner::CheckRunnable(p, *device, *ui);
      int rated = 0;
      for (const auto& t : protocols::Plan(p, 0)) rated += t.rated;
      int adaptive = 0;  // staircase / quest-plus phases: trials chosen at run time
      for (const auto& ph : p.phases) adaptive += ph.adaptive.has_value();
      fmt::print(
          "{}: ok — study '{}', {} materials, {} methods, {} criteria, {} rated trials per "
          "participant{}\n",
          *path, p.name, p.materials.size(), p.methods.size(), p.criteria.size(), rated,
          adaptive ? fmt::format(", {} adaptive phase(s) (staircase/quest-plus)", adaptive) : "");
      return kExitOk;
    });
  });
}

void RegisterStudyPlan(CLI::App* study) {
  auto path = std::make_shared<std::string>();
  auto index = std::make_shared<int>(0);
  auto code = std::make_shared<std::string>();
  auto db = std::make_shared<std::string>();
  auto as_json = std::make_shared<bool>(false);
  auto* cmd = study->add_subcommand(
      "plan",
      "Print a participant's exact trial list (deterministic from protocol, seed and plan "
      "index).\n"
      "Trials are numbered from 1, as the log, the console, events.csv and every export number\n"
      "them; plan_index in the JSON counts from 0.");
  cmd->add_option("PROTOCOL", *path, "Study protocol (.toml)")->required();
  auto* idx = cmd->add_option(
                     "--index", *index,
                     "Plan index of the participant (0-based; 'study run' gives the next free one)")
                  ->capture_default_str()
                  ->check(CLI::Range(0, std::numeric_limits<int>::max()));
  auto* part =
      cmd->add_option("--participant", *code,
                      "Participant code (e.g. P07) of a participant in --db: their plan index");
  cmd->add_option("--db", *db, "Study database, to look up --participant's plan index");
  part->excludes(idx);
  cmd->add_flag("--json", *as_json, "Print the plan as JSON");
  cmd->callback([=] {
    RunStudyGuarded([&] {
      const auto p = protocols::LoadProtocol(*path);
      if (!code->empty()) {
        if (db->empty())
          throw InputError(kCommandLine, 0, "--participant",
                           "a participant code is looked up in a study database: add --db (or "
                           "give --index N)");
        *index = runner::ParticipantIndex(*db, p.name, *code);
      }
      const auto plan = protocols::Plan(p, *index);
      if (*as_json) {
        PrintJson(json{{"study", p.name},
                       {"participant_index", *index},
                       {"participant_seed", protocols::ParticipantSeed(p, *index)},
                       {"trials", runner::PlanToJson(plan)}});
        return kExitOk;
      }
      fmt::print("study {} — participant {}plan index {} (seed {}); trials numbered from 1\n",
                 p.name, code->empty() ? "" : *code + ", ", *index,
                 protocols::ParticipantSeed(p, *index));
      fmt::print("{:>4}  {:<9} {:<16} {:<16} {:<10} {:>3}  {:<24} {:<24}\n", "#", "phase",
                 "material", "comparison", "method", "rep", "left", "right");
      for (const auto& t : plan) {
        if (t.break_before) fmt::print("      --- break ---\n");
        fmt::print("{:>4}  {:<9} {:<16} {:<16} {:<10} {:>3}  {:<24} {:<24}\n", t.index + 1,
                   protocols::ToString(t.phase), t.material, t.comparison, t.method, t.repetition,
                   t.left, t.right);
      }
      return kExitOk;
    });
  });
}

// Adds the device/actuator/screen options shared by run and resume.
void AddHardwareOptions(CLI::App* cmd, RunArgs& a) {
  cmd->add_option("--device", a.device, DeviceHelp("Haptic device back-end"))
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  cmd->add_option("--firmware", a.firmware, "Falcon firmware file (yours; docs/hardware.md)");
  AddEnumOption(cmd, "--actuator", a.actuator, runner::kActuatorNames,
                "Vibrotactile actuator: audio (PortAudio, with masking noise) or none");
  cmd->add_option("--audio-device", a.audio_device,
                  "PortAudio output device (name substring; default: the default output)");
  cmd->add_option("--full-scale", a.full_scale_mps2,
                  "Acceleration at the sound card's full scale [m/s^2] (calibration)")
      ->capture_default_str();
  cmd->add_option("--noise-rms", a.noise_rms,
                  "Masking noise level (RMS, full-scale units) when the protocol asks for it")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.5));
  cmd->add_option(
      "--rig", a.rig_file,
      "Rig file (TOML): device and sample frames, stylus tip offset, force calibration\n"
      "(docs/hardware.md; 'hapticlab rig show'). Default: the back-end's built-in rig");
  cmd->add_option("--rating-box", a.rating_box,
                  "USB HID rating box as VID:PID in hex (e.g. 16c0:05df); needs --rating-layout");
  cmd->add_option("--rating-layout", a.rating_layout,
                  "TOML layout of the box's reports (docs/hardware.md)");
  cmd->add_flag("--ui", a.ui,
                "Participant window and experimenter console (GLFW; needs a display)");
  cmd->add_flag("--fullscreen", a.fullscreen, "Participant window full screen on the last monitor");
  cmd->add_option("--ui-speed", a.ui_speed,
                  "Sim with --ui: play the simulated strokes (and the breaks) this much faster")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  AddRtOptions(cmd, a.rt);
}

// What study run and resume record and print.
void AddSessionOptions(CLI::App* cmd, RunArgs& a) {
  AddEnumOption(cmd, "--record", a.record, runner::kRecordModeNames, "What to record per trial");
  cmd->add_flag("--json", a.json, "Print the summary as JSON");
  cmd->add_flag("--quiet", a.quiet,
                "No per-trial progress (faulted attempts are still printed, on stderr)");
  cmd->add_option(
      "--consent-confirmed-by", a.consent_by,
      "Code of the experimenter who confirmed the participant's consent to the protocol's\n"
      "[consent] document and version (e.g. E01; a pseudonymous code, never a name).\n"
      "Needed when a person takes part (--ui, or a hardware device); recorded as the\n"
      "'consent' event. A simulated session records consent as not applicable.");
}

void RegisterStudyRun(CLI::App* study) {
  auto a = std::make_shared<RunArgs>();
  auto* cmd = study->add_subcommand(
      "run",
      "Run a new participant through the protocol and record everything to the database.\n"
      "Each trial's ratings commit in one transaction; after a crash use 'study resume'.\n"
      "Staircase / QUEST+ phases run after the planned ones (--device sim or falcon-twin; the\n"
      "participant answers with --ui, else the phase's simulated observer; "
      "docs/psychophysics.md).\n"
      "Exit status: 0 the session completed; 3 it stopped before its end (Abort in the console,\n"
      "Ctrl-C or SIGTERM, --stop-after, or trials that touched nothing): completed trials are\n"
      "recorded, continue with 'study resume'; 2 bad input; 1 any other failure.");
  cmd->add_option("PROTOCOL", a->protocol,
                  "Study protocol (.toml); with --plan: instead of the plan's");
  cmd->add_option("--plan", a->plan,
                  "Preregistered plan (study freeze) or imported site directory (study import):\n"
                  "verified, its protocol run, its hash recorded (docs/replication.md)");
  cmd->add_option("--db", a->db, "Study database (created when missing)")->required();
  cmd->add_option("--participant", a->participant,
                  "Pseudonymous participant code, e.g. P07: a new one, or one reserved by\n"
                  "'participant new' (it runs with its reserved plan index)")
      ->required();
  cmd->add_option("--index", a->index,
                  "Plan index of the participant (default: the reserved or the next free one)")
      ->check(CLI::Range(0, std::numeric_limits<int>::max()));
  AddHardwareOptions(cmd, *a);
  AddSessionOptions(cmd, *a);
  cmd->add_option("--stop-after", a->stop_after, "Abort after this many trials (to test resume)");
  cmd->add_option("--inject-faults", a->fault_rate, "Sim: probability of a device fault per trial")
      ->check(CLI::Range(0.0, 0.9));
  cmd->add_option("--site", a->site,
                  "Site code recorded with the session: a short pseudonymous code (up to 8\n"
                  "characters, e.g. S02; never a lab's name); default: the site code of a\n"
                  "--plan site directory (study import --site), else L0. 'db merge' keeps sites\n"
                  "apart (docs/replication.md, \"Combining sites\")")
      ->capture_default_str();
  cmd->add_option("--site-offset", a->site_offset,
                  "Simulated observer: add this many rating points to every rating (a site\n"
                  "effect, for replication examples and tests)")
      ->check(CLI::Range(-50.0, 50.0));
  cmd->callback([a, cmd] {
    RunStudyGuarded([&] {
      runner::RunOptions o;
      const auto p = LoadRunProtocol(a->protocol, a->plan, &o, a->quiet || a->json);
      stats::CheckAnalyses(p);
      o.participant_index = a->index;
      o.fault_rate = a->fault_rate;
      // An imported site directory names its site; --site given wins (the provenance keeps
      // the directory's as plan_site).
      o.site = (cmd->count("--site") == 0 && !o.plan_site.empty()) ? o.plan_site : a->site;
      o.site_offset = a->site_offset;
      return RunSession(*a, p.name, o,
                        [&](const runner::RunOptions& ro) { return runner::RunStudy(p, ro); });
    });
  });
}

void RegisterStudyResume(CLI::App* study) {
  auto a = std::make_shared<RunArgs>();
  auto* cmd = study->add_subcommand(
      "resume",
      "Continue a participant's session where a crash, abort or signal left it, in the mode it "
      "was\n"
      "recorded in (device, actuator, --ui, rating box): those options default to the recorded\n"
      "ones, and a different mode is refused unless --change-mode is given (then it is logged).\n"
      "Exit status as for 'study run': 0 completed, 3 stopped again.");
  cmd->add_option("--db", a->db, "Study database")->required();
  cmd->add_option("--participant", a->participant, "Participant code")->required();
  cmd->add_option("--stop-after", a->stop_after, "Abort again after this many trials (tests)");
  AddHardwareOptions(cmd, *a);
  AddSessionOptions(cmd, *a);
  cmd->add_flag(
      "--change-mode", a->change_mode,
      "Continue in the mode these options give although it differs from the recorded one\n"
      "(logged as a 'mode-change' event; every rating records its source)");
  cmd->callback([a, cmd] {
    RunStudyGuarded([&] {
      // Options not given take the recorded mode's values.
      const auto rec = runner::RecordedMode(a->db, a->participant);
      if (cmd->count("--device") == 0) a->device = rec.device;
      if (cmd->count("--actuator") == 0 && rec.actuator) a->actuator = *rec.actuator;
      if (cmd->count("--ui") == 0) a->ui = rec.screens;
      if (cmd->count("--rating-box") == 0 && rec.rater.kind == runner::RaterKind::kRatingBox)
        a->rating_box = rec.rater.box;
      a->recorded_mode = rec.Describe();
      // Refused before any device or window is opened.
      runner::CheckResumeMode(
          rec, {a->device, a->actuator, a->ui, runner::RaterOf(a->ui, a->rating_box)},
          a->change_mode, a->db, a->participant);
      runner::RunOptions o;
      o.change_mode = a->change_mode;
      return RunSession(*a, rec.study, o,
                        [](const runner::RunOptions& ro) { return runner::ResumeStudy(ro); });
    });
  });
}

}  // namespace

void RegisterStudy(CLI::App& app) {
  auto* study = app.add_subcommand(
      "study", "Study protocols: validate, plan, run, resume, status (docs/studies.md)");
  study->require_subcommand(1);
  RegisterPower(*study);
  RegisterCalibrate(*study);
  RegisterStudyPreregistration(*study);
  RegisterStudyValidate(study);
  RegisterStudyPlan(study);
  RegisterStudyRun(study);
  RegisterStudyResume(study);
  RegisterStudyStatus(*study);
}

}  // namespace hapticlab::cli
