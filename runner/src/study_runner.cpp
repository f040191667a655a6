#include "hapticlab/runner/study_runner.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>
#include <set>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "adaptive_phase.hpp"
#include "stimulus_side.hpp"

namespace hapticlab::runner {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using protocols::PhaseKind;
using sim::Observer;
using sim::ProfileSet;

// The stop request of RequestStop (a signal number; 0: none). Lock-free, so a signal
// handler may store to it.
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

// Back-ends whose sessions are simulated (a simulated hand, the simulated observer).
bool IsSimulated(const std::string& device) { return device == "sim" || device == "falcon-twin"; }

// Everything a session needs besides the database: models, profiles, observer.
struct Lab {
  const protocols::Protocol* protocol = nullptr;
  ProfileSet profiles;
  std::map<std::string, renderer::MaterialModel> models;  // by material id
  std::map<std::string, std::string> model_hashes;
};

// Loads the profiles (ground truth of each sample) and every material's model. Files are
// looked up relative to the protocol file's folder. Every problem is collected (file, line,
// key, and the path looked up), then thrown together: `study validate` reports the same.
Lab LoadLab(const protocols::Protocol& p, const std::string& device) {
  const bool sim = IsSimulated(device);
  Lab lab;
  lab.protocol = &p;
  const fs::path dir = fs::path(p.file).parent_path();
  Diagnostics d;
  // Runs `load`; an input or I/O error becomes a diagnostic (at `line`, `field` when the
  // error names no file of its own).
  const auto attempt = [&](int line, const std::string& field, const auto& load) {
    try {
      load();
      return true;
    } catch (const InputError& e) {
      for (const auto& x : e.diagnostics()) d.Add(x.file, x.line, x.field, x.message);
    } catch (const std::exception& e) {
      d.Add(p.file, line, field, e.what());
    }
    return false;
  };
  const auto where = [&](const std::string& name) {
    return fmt::format("'{}' (looked up relative to the protocol's folder: {})", name,
                       fs::absolute(dir / name).lexically_normal().string());
  };
  if (p.profiles.empty() && sim)
    d.Add(p.file, 0, "study.profiles", "the simulated lab needs a profiles file (ground truth of each sample)");
  bool have_profiles = false;
  if (!p.profiles.empty()) {
    if (!fs::is_regular_file(dir / p.profiles))
      d.Add(p.file, 0, "study.profiles", "no such file " + where(p.profiles));
    else
      have_profiles = attempt(0, "study.profiles", [&] { lab.profiles = sim::LoadProfiles((dir / p.profiles).string()); });
  }
  if (!p.observer.empty()) {
    if (!fs::is_regular_file(dir / p.observer))
      d.Add(p.file, 0, "study.observer", "no such file " + where(p.observer));
    else
      attempt(0, "study.observer", [&] { lab.profiles.observer = sim::LoadObserver((dir / p.observer).string()); });
  }
  for (const auto& m : p.materials) {
    const bool placeholder = m.model == "placeholder";
    if (!placeholder) {
      if (!fs::is_regular_file(dir / m.model)) {
        d.Add(p.file, m.line, "material.model", "material '" + m.id + "': no model file " + where(m.model));
      } else {
        const std::string path = (dir / m.model).string();
        attempt(m.line, "material.model", [&] {
          auto model = renderer::LoadMaterial(path);
          lab.model_hashes[m.id] = db::HashText(ReadTextFile(path));
          lab.models.emplace(m.id, std::move(model));
        });
      }
      if (!sim) continue;  // hardware: the fitted model is all it needs
    }
    // The simulated lab (and a placeholder model) needs the sample's profile.
    if (p.profiles.empty()) {
      if (!sim) d.Add(p.file, m.line, "material.model", "material '" + m.id + "': a placeholder model is built from the "
                                                        "sample's profile, and the protocol names no profiles file");
      continue;
    }
    if (!have_profiles) continue;  // the profiles file's own problem is reported above
    const auto prof = lab.profiles.profiles.find(m.profile);
    if (prof == lab.profiles.profiles.end()) {
      d.Add(p.file, m.line, "material.profile",
            "material '" + m.id + "': no profile '" + m.profile + "' in " + p.profiles + " (its profiles: " +
                [&] {
                  std::string names;
                  for (const auto& [name, pr] : lab.profiles.profiles) names += (names.empty() ? "" : ", ") + name;
                  return names.empty() ? std::string("none") : names;
                }() + ")");
      continue;
    }
    if (placeholder) {
      auto model = sim::PlaceholderModel(prof->second);
      lab.model_hashes[m.id] = db::HashText(renderer::MaterialToToml(model));
      lab.models.emplace(m.id, std::move(model));
    }
  }
  d.ThrowIfAny();
  return lab;
}

struct Outcome {
  bool aborted = false;  // the experimenter aborted in the UI
  bool fault = false;
  bool untouched = false;  // a side where the stylus never met the surface
  std::string fault_detail;
  std::vector<db::Rating> ratings;
  double stimulus_s = 0;
};

// The participant's ratings from the UI, clamped to the scale, with the response time from
// the rating screen's appearance; false when the experimenter aborted.
bool RateInUi(SessionUi& ui, const TrialScreen& screen, const protocols::Protocol& p, const std::string& source,
              std::vector<db::Rating>* out) {
  const auto shown = std::chrono::steady_clock::now();
  const auto r = ui.Rate(screen);
  if (!r || r->size() != p.criteria.size()) return false;
  const double rt = std::chrono::duration<double>(std::chrono::steady_clock::now() - shown).count();
  for (std::size_t i = 0; i < p.criteria.size(); ++i)
    out->push_back({p.criteria[i], std::clamp((*r)[i], p.scale_min, p.scale_max), rt, source});
  return true;
}

TrialScreen ScreenOf(const protocols::Protocol& p, const db::Trial& t, int index, int total) {
  TrialScreen s;
  s.index = index;
  s.total = total;
  s.phase = t.phase;
  s.left = t.left;
  s.right = t.right;
  s.method = t.method;
  auto what = [](const std::string& stim) {
    const auto colon = stim.find(':');
    const std::string kind = stim.substr(0, colon), id = stim.substr(colon + 1);
    return kind == "real" ? "the real " + id + " sample" : "virtual (" + id + ")";
  };
  s.placement = t.right.empty() ? fmt::format("left: {}; right: nothing", what(t.left))
                                : fmt::format("left: {}; right: {}", what(t.left), what(t.right));
  s.criteria = p.criteria;
  s.scale_min = p.scale_min;
  s.scale_max = p.scale_max;
  return s;
}

// Runs one trial, simulated or on hardware, through the one trial path: each side for the
// stimulus duration through internal::RunStimulusSide (the method's renderer, or for a real
// sample zero force: the device only measures, inside the real-time engine over the rig's
// device and actuator, with the watchdog and the trajectory writer). A watchdog fault in
// either side faults the trial; a side that touched nothing is reported. Ratings come from
// the participant window, or on a simulated rig without one from the simulated observer
// rating what the hand felt.
Outcome ExecuteTrial(const Lab& lab, const Observer& observer, const db::Trial& t, std::uint64_t participant_seed,
                     const RunOptions& opt, HardwareRig& rig, db::TrajectoryWriter* writer, const TrialScreen& screen,
                     db::Database& database, std::int64_t session) {
  const auto& p = *lab.protocol;
  Outcome out;
  const std::uint64_t trial_seed =
      DeriveSeed(participant_seed, static_cast<std::uint64_t>(t.plan_index) * 64 + static_cast<std::uint64_t>(t.attempts));
  Rng rng(trial_seed);
  const double dur = p.stimulus_duration_s;
  const bool simulated = rig.sim != nullptr;
  if (t.phase == "training") {
    // Training (ch. V.2.1): each virtual sample in turn, explored freely for the phase's
    // duration, not rated. A simulated participant without screens learns nothing from it,
    // so such a session records the trial without rendering it.
    if (simulated && !opt.ui) return out;
    const protocols::Phase* phase = nullptr;
    for (const auto& ph : p.phases)
      if (ph.kind == PhaseKind::kTraining) phase = &ph;
    const std::string id = t.left.substr(t.left.find(':') + 1);
    internal::StimulusSide s;
    s.model = &lab.models.at(id);
    s.real = t.left.rfind("real:", 0) == 0;  // plans from before virtual training: the real sample
    const auto* method = p.FindMethod(t.method);
    if (!s.real && method) s.options = internal::MethodOptions(*method, DeriveSeed(trial_seed, 0));
    s.real = s.real || !method;
    s.sample = 0;
    if (simulated) s.stroke = sim::DrawStroke(rng);
    if (simulated && s.real) {
      s.truth = &lab.profiles.profiles.at(p.FindMaterial(id)->profile);
      s.truth_seed = rng.NextU64();
    }
    s.stream = "left";
    s.label = "training sample";
    s.stimulus = t.left;
    const double train_s = phase ? phase->duration_s : dur;
    const auto r = internal::RunStimulusSide(s, rig, train_s, opt, writer, database, session, t, screen, 0);
    out.aborted = r.aborted;
    out.stimulus_s = train_s;
    // A fault while training is logged (the watchdog zeroed the force) but the unrated trial
    // is not repeated: a device that keeps faulting is caught by the rated trials.
    if (r.fault) {
      database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "device-fault",
                         .detail = "watchdog: " + r.detail + "; force was zeroed; training trial not repeated"});
      if (opt.ui) opt.ui->Event(fmt::format("training trial {}: {}", t.plan_index + 1, r.detail));
    }
    return out;
  }
  // The simulated participant's exploration: one stroke, the same with ~10 % variation on
  // the other side.
  std::array<sim::Stroke, 2> strokes{};
  if (simulated) {
    strokes[0] = sim::DrawStroke(rng);
    strokes[1] = sim::JitterStroke(strokes[0], rng);
  }
  const bool inject_dropout = simulated && opt.fault_rate > 0 && rng.Uniform() < opt.fault_rate;
  std::array<sim::Features, 2> felt{};
  std::vector<std::string> faults, untouched;
  for (int side = 0; side < 2; ++side) {
    const std::string& stim = side == 0 ? t.left : t.right;
    const auto colon = stim.find(':');
    const std::string kind = stim.substr(0, colon), id = stim.substr(colon + 1);
    internal::StimulusSide s;
    s.model = &lab.models.at(id);
    s.real = kind == "real";
    if (!s.real)
      s.options = internal::MethodOptions(*p.FindMethod(t.method), DeriveSeed(trial_seed, static_cast<std::uint64_t>(side)));
    s.sample = side;
    s.stroke = strokes[static_cast<std::size_t>(side)];
    if (simulated && s.real) {
      s.truth = &lab.profiles.profiles.at(p.FindMaterial(id)->profile);
      s.truth_seed = rng.NextU64();
    }
    s.dropout_at_s = inject_dropout && side == 0 ? 0.3 * dur : -1;
    s.stream = side == 0 ? "left" : "right";
    s.label = s.stream + " side";
    s.stimulus = stim;
    s.report_side = side;
    const auto r = internal::RunStimulusSide(s, rig, dur, opt, writer, database, session, t, screen, side);
    if (r.fault) faults.push_back(r.detail);
    if (r.untouched) untouched.push_back(r.detail);
    felt[static_cast<std::size_t>(side)] = r.felt;
    if (r.aborted) {
      out.aborted = true;
      return out;
    }
    out.stimulus_s += dur;
  }
  if (!faults.empty()) {
    out.fault = true;
    out.fault_detail = "watchdog: " + fmt::format("{}", fmt::join(faults, "; ")) + "; force was zeroed, trial re-queued";
    return out;
  }
  if (!untouched.empty()) {
    out.fault = out.untouched = true;
    out.fault_detail = "nothing was touched: " + fmt::format("{}", fmt::join(untouched, "; ")) +
                       "; check the rig's sample poses (hapticlab rig show); trial re-queued";
    return out;
  }
  if (opt.ui) {
    out.aborted = !RateInUi(*opt.ui, screen, p, opt.rating_input, &out.ratings);
    return out;
  }
  if (opt.on_felt) {
    FeltTrial ft{.plan_index = t.plan_index, .phase = t.phase, .material = t.material, .comparison = t.comparison,
                 .method = t.method, .repetition = t.repetition, .distances = {}, .felt = felt};
    for (const auto& c : p.criteria) ft.distances.push_back(observer.Distance(c, felt[0], felt[1]));
    opt.on_felt(ft);
  }
  for (const auto& c : p.criteria)
    out.ratings.push_back({c, observer.Rate(c, t.material, t.method, felt[0], felt[1], p.scale_min, p.scale_max, rng),
                           Observer::ResponseTime(rng), db::kRaterSimulated});
  return out;
}

void Log(const RunOptions& o, const std::string& s) {
  if (o.log) o.log(s);
}

// Executes the session's remaining trials. Faulted trials go to the end of their phase.
RunSummary Execute(db::Database& database, const Lab& lab, std::int64_t session, const db::Participant& part,
                   const RunOptions& opt) {
  const auto& p = *lab.protocol;
  const auto t0 = std::chrono::steady_clock::now();
  RunSummary sum;
  sum.session_id = session;
  sum.participant = part.code;
  const Observer observer(lab.profiles.observer, DeriveSeed(part.seed, 0xABCDEF), p.criteria);
  // Without a rig, a simulated session builds the generic simulated rig.
  std::unique_ptr<sim::SimRig> own_sim;
  HardwareRig own_rig;
  HardwareRig* rig = opt.rig;
  if (!rig) {
    if (opt.device != "sim")
      throw InputError("", 0, "--device",
                       "a hardware session needs an opened device and the participant window (--ui) for the ratings");
    own_sim = std::make_unique<sim::SimRig>(sim::SimDeviceModel{.seed = DeriveSeed(part.seed, 0x51D)}, sim::DefaultSamplePoses());
    own_rig.device = own_sim->device;
    own_rig.actuator = &own_sim->actuator;
    own_rig.device_from_sample = own_sim->true_device_from_sample;
    own_rig.sim = own_sim.get();
    own_rig.description = "sim (generic simulated device, simulated hand)";
    rig = &own_rig;
  }
  if (!rig->device || (!rig->sim && !opt.ui))
    throw InputError("", 0, "--device",
                     "a hardware session needs an opened device and the participant window (--ui) for the ratings");
  if (opt.device != "sim" || opt.rig) database.LogEvent({.session_id = session, .kind = "device", .detail = rig->description});
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
      database.LogEvent({.session_id = session, .trial_id = trial_under_way, .kind = kind, .detail = detail});
    };
  const bool constrained = p.randomization.no_immediate_repeat;
  int untouched_in_a_row = 0;
  std::set<std::int64_t> break_before;  // trials the plan puts a break before
  for (const auto& e : database.Events(session))
    if (e.kind == "break-planned" && e.trial_id) break_before.insert(*e.trial_id);
  for (const char* phase : {"training", "reference", "main"}) {
    std::vector<db::Trial> queue;
    for (const auto& t : trials)
      if (t.phase == phase && t.status != db::kTrialCompleted && t.status != db::kTrialFaulted) queue.push_back(t);
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
          database.LogEvent({.session_id = session, .trial_id = queue[0].id, .kind = "constraint-relaxed",
                             .detail = "only trials of the same material remain in the phase"});
      }
      db::Trial t = queue[pick];
      queue.erase(queue.begin() + static_cast<std::ptrdiff_t>(pick));
      if (const int sig = StopRequested()) {
        database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "interrupted",
                           .detail = fmt::format("stopped by signal {} ({}) before this trial; 'study resume' "
                                                 "continues with it",
                                                 sig, sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "signal")});
        database.EndSession(session, "aborted");
        sum.status = "aborted";
        sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return sum;
      }
      if (opt.stop_after_trials >= 0 && sum.executed >= opt.stop_after_trials) {
        database.LogEvent({.session_id = session, .kind = "abort", .detail = "stopped after the requested number of trials"});
        database.EndSession(session, "aborted");
        sum.status = "aborted";
        sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return sum;
      }
      const bool requested = opt.ui && opt.ui->TakeBreakNow();
      if (opt.ui && (requested || (break_before.count(t.id) && t.phase != std::string("training")))) {
        // A simulated session played faster (--ui-speed) shortens its breaks alike.
        const double speed = rig->sim ? opt.ui_playback_speed : 1.0;
        const double break_s = p.break_duration_s / speed;
        database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "break",
                           .detail = fmt::format("{:.0f} s break ({}{})", break_s,
                                                 requested ? "requested by the experimenter" : "planned",
                                                 speed != 1.0 ? fmt::format("; --ui-speed {:g}", speed) : "")});
        trial_under_way = t.id;
        if (!opt.ui->Break(break_s)) {
          database.LogEvent({.session_id = session, .kind = "abort", .detail = "the experimenter aborted during a break"});
          database.EndSession(session, "aborted");
          sum.status = "aborted";
          sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          return sum;
        }
      }
      database.StartTrial(t.id);
      ++t.attempts;
      ++sum.executed;
      const bool training = t.phase == std::string("training");
      auto screen = ScreenOf(p, t, training ? training_done + 1 : rated_done + 1, training ? training_total : rated_total);
      screen.training = training;
      screen.rated_done = rated_done;
      screen.rated_total = rated_total;
      screen.training_done = training_done;
      screen.training_total = training_total;
      trial_under_way = t.id;
      const Outcome o = ExecuteTrial(lab, observer, t, part.seed, opt, *rig, &writer, screen, database, session);
      sum.simulated_s += o.stimulus_s;
      untouched_in_a_row = o.untouched ? untouched_in_a_row + 1 : 0;
      if (o.aborted) {
        database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "abort",
                           .detail = "the experimenter aborted in the console; 'study resume' continues with this trial"});
        database.EndSession(session, "aborted");
        sum.status = "aborted";
        sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return sum;
      }
      if (o.fault) {
        ++sum.faults;
        database.SetTrialStatus(t.id, db::kTrialFaulted);
        database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "device-fault", .detail = o.fault_detail});
        if (opt.ui) opt.ui->Event(fmt::format("{} {}: {} (re-queued)", training ? "training trial" : "trial", screen.index, o.fault_detail));
        t.status = db::kTrialFaulted;
        queue.push_back(t);
        if (untouched_in_a_row >= opt.max_untouched_trials) {
          database.LogEvent({.session_id = session, .kind = "abort",
                             .detail = fmt::format("{} trials in a row touched nothing: the rig's sample poses are "
                                                   "probably wrong (hapticlab rig show / rig calibrate)",
                                                   untouched_in_a_row)});
          database.EndSession(session, "aborted");
          sum.status = "aborted";
          sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          return sum;
        }
        continue;
      }
      // The ratings commit only with every trajectory stream of this attempt whole.
      try {
        database.CompleteTrial(t.id, o.ratings, writer.TakeReports(t.id));
        trajectory_faults = 0;
      } catch (const db::TrajectoryIncomplete& e) {
        ++sum.faults;
        database.SetTrialStatus(t.id, db::kTrialFaulted);
        database.LogEvent({.session_id = session, .trial_id = t.id, .kind = "trajectory-fault", .detail = e.what()});
        if (opt.ui) opt.ui->Event(fmt::format("{} {}: trajectories not stored (re-queued)", training ? "training trial" : "trial", screen.index));
        if (++trajectory_faults >= kMaxTrajectoryFaults) {
          database.EndSession(session, "aborted");
          throw std::runtime_error(fmt::format("{} trials in a row could not store their trajectories; last: {}; "
                                               "fix the cause, then 'hapticlab study resume'",
                                               trajectory_faults, e.what()));
        }
        t.status = db::kTrialFaulted;
        queue.push_back(t);
        continue;
      }
      ++sum.completed;
      (training ? training_done : rated_done) += 1;
      last_material = t.material;
      Log(opt, fmt::format("{} trial {}/{} ({} {} {}) done", part.code, sum.completed, sum.planned, t.phase, t.material,
                           t.method.empty() ? t.comparison : t.method));
    }
  }
  // Adaptive phases (staircase, QUEST+): trials chosen one by one from the answers so far.
  const auto adaptive = internal::RunAdaptivePhases(database, session, p, lab.models, part.seed, opt, *rig, &writer, &sum.executed);
  sum.planned += adaptive.added;
  sum.completed += adaptive.completed;
  sum.faults += adaptive.faults;
  sum.simulated_s += adaptive.stimulus_s;
  if (adaptive.aborted) {
    sum.status = "aborted";
    sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return sum;
  }
  database.EndSession(session, "completed");
  sum.status = "completed";
  sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sum;
}

// Breaks and phase changes are logged as the plan reaches them.
void LogPlanEvents(db::Database& database, std::int64_t session, const std::vector<protocols::PlannedTrial>& plan,
                   const std::vector<std::int64_t>& ids, const protocols::Protocol& p) {
  for (std::size_t i = 0; i < plan.size(); ++i)
    if (plan[i].break_before)
      database.LogEvent({.session_id = session, .trial_id = ids[i], .kind = "break-planned",
                         .detail = fmt::format("{:.0f} s break before this trial", p.break_duration_s)});
}

// Checkpoints the WAL into the main file when a session ends, however it ends (completed,
// aborted, interrupted by a signal, or an error): the database file alone then holds every
// committed rating. Runs after Execute's trajectory writer has closed its connection.
struct CheckpointAtEnd {
  db::Database* database;
  ~CheckpointAtEnd() {
    try {
      database->Checkpoint();
    } catch (...) {  // never throw from a destructor; the -wal still holds the data
    }
  }
};

}  // namespace

std::string SessionMode::Describe() const {
  return fmt::format("device {}, actuator {}, screens {}, ratings {}", device, actuator, screens ? "on" : "off",
                     rater == db::kRaterSimulated ? "simulated" : "by the participant (" + rater + ")");
}

bool CheckResumeMode(const SessionMode& recorded, const SessionMode& now, bool change_mode,
                     const std::string& db_path, const std::string& participant) {
  const bool differs = now.device != recorded.device || now.screens != recorded.screens ||
                       now.rater != recorded.rater ||
                       (recorded.actuator != "unrecorded" && now.actuator != recorded.actuator);
  if (differs && !change_mode)
    throw InputError(db_path, 0, "--participant",
                     fmt::format("{}'s session was recorded in mode [{}]; this resume asks for [{}]. Resume "
                                 "without those options to continue in the recorded mode, or add --change-mode "
                                 "to continue in the new one (logged; each rating records its source)",
                                 participant, recorded.Describe(), now.Describe()));
  return differs;
}

SessionMode ModeOf(const RunOptions& o) {
  return {o.device, o.actuator, o.ui != nullptr, o.ui ? o.rating_input : std::string(db::kRaterSimulated)};
}

SessionMode RecordedMode(const std::string& db_path, const std::string& participant) {
  if (!fs::exists(db_path)) throw InputError(db_path, 0, "--db", "no such database");
  const db::Database database = db::OpenForReading(db_path);
  for (const auto& st : database.Studies())
    if (const auto part = database.FindParticipant(st.id, participant)) {
      const auto sessions = database.Sessions(part->id);
      if (sessions.empty()) break;
      const auto& se = sessions.back();
      return {se.device, se.actuator, se.screens, se.rater};
    }
  throw InputError(db_path, 0, "--participant", "no participant " + participant + " with a session in this database");
}

void CheckRunnable(const protocols::Protocol& p, const std::string& device, bool ui) {
  internal::CheckAdaptivePhases(p, device, ui);
  (void)LoadLab(p, device);
}

int ParticipantIndex(const std::string& db_path, const std::string& study, const std::string& code) {
  if (!fs::exists(db_path)) throw InputError(db_path, 0, "--db", "no such database");
  const db::Database database = db::OpenForReading(db_path);
  const auto st = database.FindStudy(study);
  if (!st) throw InputError(db_path, 0, "--participant", "no study '" + study + "' in this database");
  const auto part = database.FindParticipant(st->id, code);
  if (!part)
    throw InputError(db_path, 0, "--participant",
                     "no participant " + code + " in study '" + study + "' (a code not yet run has no plan index; "
                     "use --index N)");
  return part->index;
}

void RequestStop(int signal_number) noexcept { g_stop_signal.store(signal_number); }
int StopRequested() noexcept { return g_stop_signal.load(); }

RunSummary RunStudy(const protocols::Protocol& p, const RunOptions& opt) {
  protocols::CheckParticipantCode(p, opt.participant);  // before anything is written
  internal::CheckAdaptivePhases(p, opt.device, opt.ui != nullptr);
  const Lab lab = LoadLab(p, opt.device);
  const db::WriterLease lease(opt.db_path);  // one writer per study database
  db::Database database(opt.db_path);
  const std::string hash = db::HashText(p.text);
  const SessionMode mode = ModeOf(opt);
  std::int64_t study_id;
  if (auto s = database.FindStudy(p.name)) {
    if (s->protocol_hash != hash)
      throw InputError(opt.db_path, 0, "study",
                       "study '" + p.name + "' in this database was run with a different protocol text (hash " +
                           s->protocol_hash.substr(0, 12) + "); use a new database or restore the protocol");
    study_id = s->id;
  } else {
    study_id = database.CreateStudy({.name = p.name, .protocol_toml = p.text, .protocol_hash = hash, .seed = p.seed});
  }
  if (database.FindParticipant(study_id, opt.participant))
    throw InputError(opt.db_path, 0, "--participant",
                     "participant " + opt.participant + " already has a session; continue it with 'hapticlab study resume'");
  const int index = opt.participant_index >= 0 ? opt.participant_index : static_cast<int>(database.Participants(study_id).size());
  const db::Participant part{.study_id = study_id, .code = opt.participant, .index = index,
                             .seed = protocols::ParticipantSeed(p, index)};
  const auto plan = protocols::Plan(p, index);
  // Provenance: everything needed to reproduce this session.
  json models = json::object();
  for (const auto& [id, h] : lab.model_hashes) models[id] = h;
  json plan_json = json::array();
  for (const auto& t : plan)
    plan_json.push_back({{"index", t.index}, {"phase", protocols::ToString(t.phase)}, {"material", t.material},
                         {"comparison", t.comparison}, {"method", t.method}, {"repetition", t.repetition},
                         {"left", t.left}, {"right", t.right}, {"rated", t.rated}, {"break_before", t.break_before}});
  const json prov = {{"protocol_hash", hash},
                     // Relative to the database's folder (an absolute path would carry a user name).
                     {"protocol_path", fs::weakly_canonical(fs::absolute(p.file))
                                           .lexically_relative(fs::weakly_canonical(fs::absolute(opt.db_path)).parent_path())
                                           .string()},
                     {"study_seed", p.seed},
                     {"participant_index", index},
                     {"participant_seed", part.seed},
                     {"software", std::string(kVersion) + "+" + kGitSha},
                     {"device", opt.device},
                     {"rig", opt.rig ? json{{"description", opt.rig->description},
                                            {"file_sha256", opt.rig->rig_file_hash},
                                            {"content", opt.rig->calibration}}
                                     : json{{"description", "generic simulated rig"}}},
                     {"model_hashes", models},
                     {"masking_noise", {{"enabled", p.masking_noise}, {"level_dB", p.masking_level_dB}}}};
  // Participant, session, plan and consent in one transaction: a crash leaves all or none.
  database.Exec("BEGIN IMMEDIATE");
  std::int64_t session;
  std::vector<std::int64_t> ids;
  try {
    const auto pid = database.AddParticipant(part);
    session = database.StartSession({.participant_id = pid,
                                     .software_version = std::string(kVersion) + "+" + kGitSha,
                                     .device = opt.device,
                                     .calibration = opt.rig ? opt.rig->calibration : "simulated (no calibration)",
                                     .provenance_json = prov.dump(),
                                     .plan_json = plan_json.dump(),
                                     .actuator = mode.actuator,
                                     .screens = mode.screens,
                                     .rater = mode.rater});
    std::vector<db::Trial> rows;
    for (const auto& t : plan)
      rows.push_back({.session_id = session, .plan_index = t.index, .phase = protocols::ToString(t.phase),
                      .material = t.material, .comparison = t.comparison, .method = t.method,
                      .repetition = t.repetition, .left = t.left, .right = t.right});
    for (const auto& r : rows) ids.push_back(database.AddTrial(r));
    database.LogEvent({.session_id = session, .kind = "consent",
                       .detail = mode.rater == db::kRaterSimulated ? "simulated participant" : "consent form signed"});
    LogPlanEvents(database, session, plan, ids, p);
    database.Exec("COMMIT");
  } catch (...) {
    database.Exec("ROLLBACK");
    throw;
  }
  Log(opt, fmt::format("{}: session {} with {} planned trials ({})", opt.participant, session, plan.size(),
                       mode.Describe()));
  db::Participant stored = *database.FindParticipant(study_id, opt.participant);
  const CheckpointAtEnd checkpoint{&database};
  return Execute(database, lab, session, stored, opt);
}

RunSummary ResumeStudy(const RunOptions& opt) {
  if (!fs::exists(opt.db_path)) throw InputError(opt.db_path, 0, "--db", "no such database");
  const db::WriterLease lease(opt.db_path);  // one writer per study database
  db::Database database(opt.db_path);
  for (const auto& st : database.Studies()) {
    const auto part = database.FindParticipant(st.id, opt.participant);
    if (!part) continue;
    const auto sessions = database.Sessions(part->id);
    if (sessions.empty()) throw InputError(opt.db_path, 0, "--participant", opt.participant + " has no session");
    const auto& se = sessions.back();
    if (se.status == "completed")
      throw InputError(opt.db_path, 0, "--participant", opt.participant + "'s session is already completed");
    const json prov = json::parse(se.provenance_json);
    // Stored relative to the database's folder (older sessions: absolute).
    const std::string stored = prov.value("protocol_path", "");
    const std::string path =
        stored.empty() ? stored
                       : (fs::weakly_canonical(fs::absolute(opt.db_path)).parent_path() / stored).lexically_normal().string();
    // The protocol text comes from the database; its folder (for models and profiles) from
    // where it was run.
    auto p = protocols::ParseProtocol(st.protocol_toml, path);
    if (!path.empty() && fs::exists(path) && db::HashText(ReadTextFile(path)) != st.protocol_hash)
      Log(opt, "note: the protocol file on disk changed since the session began; resuming with the recorded text");
    // The recorded mode, or with --change-mode the new one (logged).
    const SessionMode recorded{se.device, se.actuator, se.screens, se.rater};
    const SessionMode now = ModeOf(opt);
    const bool differs = CheckResumeMode(recorded, now, opt.change_mode, opt.db_path, opt.participant);
    const Lab lab = LoadLab(p, opt.device);
    if (differs) {
      database.LogEvent({.session_id = se.id, .kind = "mode-change",
                         .detail = fmt::format("resumed with --change-mode: [{}] -> [{}]", recorded.Describe(),
                                               now.Describe())});
      database.SetSessionMode(se.id, now.device, now.actuator, now.screens, now.rater);
      Log(opt, fmt::format("{}: mode changed from [{}] to [{}]", opt.participant, recorded.Describe(), now.Describe()));
    } else if (recorded.actuator == "unrecorded") {
      database.SetSessionMode(se.id, now.device, now.actuator, now.screens, now.rater);
    }
    const RunOptions& o = opt;
    database.Exec(fmt::format("UPDATE session SET status='running', ended_at=NULL WHERE id={}", se.id));
    int done = 0;
    for (const auto& t : database.Trials(se.id)) done += t.status == db::kTrialCompleted;
    database.LogEvent({.session_id = se.id, .kind = "resume",
                       .detail = fmt::format("resumed with {} of {} trials completed", done, database.Trials(se.id).size())});
    Log(opt, fmt::format("{}: resuming session {} ({} trials completed; {})", opt.participant, se.id, done,
                         now.Describe()));
    const CheckpointAtEnd checkpoint{&database};
    return Execute(database, lab, se.id, *part, o);
  }
  throw InputError(opt.db_path, 0, "--participant", "no participant " + opt.participant + " in this database");
}

std::vector<ParticipantStatus> StudyStatus(const std::string& db_path, const std::string& participant) {
  if (!fs::exists(db_path)) throw InputError(db_path, 0, "--db", "no such database");
  const db::Database database = db::OpenForReading(db_path);  // quick_check; migrates an older file
  std::vector<ParticipantStatus> out;
  for (const auto& st : database.Studies())
    for (const auto& part : database.Participants(st.id)) {
      if (!participant.empty() && part.code != participant) continue;
      ParticipantStatus s;
      s.code = part.code;
      std::map<int, int> completions;
      for (const auto& se : database.Sessions(part.id)) {
        s.session_status = se.status;
        for (const auto& t : database.Trials(se.id)) {
          ++s.planned;
          if (t.status == db::kTrialCompleted) {
            ++s.completed;
            ++completions[t.plan_index];
          }
          if (t.status == db::kTrialFaulted) ++s.faulted;
        }
      }
      for (const auto& [i, c] : completions) s.duplicates += c > 1 ? c - 1 : 0;
      out.push_back(s);
    }
  if (!participant.empty() && out.empty())
    throw InputError(db_path, 0, "--participant", "no participant " + participant + " in this database");
  return out;
}

}  // namespace hapticlab::runner
