#include "adaptive_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/psychophysics/quest_plus.hpp"
#include "hapticlab/psychophysics/staircase.hpp"
#include "hapticlab/runner/audit.hpp"
#include "hapticlab/sim/psychophysical_observer.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "stimulus_side.hpp"

namespace hapticlab::runner::internal {
namespace {

using protocols::AdaptiveSpec;
using protocols::PhaseKind;

// What an adaptive trial records (rating rows of the trial, committed with its completion
// marker in one transaction; docs/psychophysics.md).
constexpr const char* kLevel = "level";        // x = comparison - reference [parameter unit]
constexpr const char* kResponse = "response";  // chosen interval (1-based) or 1 yes / 0 no
constexpr const char* kCorrect = "correct";    // 1 positive (correct or yes), 0 not
constexpr const char* kInterval = "interval";  // the comparison's interval (1-based); 0 in yes/no
constexpr const char* kPhase = "phase";        // index of the phase in the protocol (0-based)

struct Answered {
  std::int64_t trial_id = 0;
  int track = 0;
  double level = 0;
  bool positive = false;
};

double RatingOf(const std::vector<db::Rating>& rs, const char* name) {
  for (const auto& r : rs)
    if (r.criterion == name) return r.score;
  throw std::runtime_error(fmt::format("adaptive trial without a '{}' record", name));
}

// The phase's recorded trials: completed ones in plan order, and the one left unfinished
// (crash, abort or fault), which is retried.
void History(db::Database& database, std::int64_t session, std::size_t phase_index, PhaseKind kind,
             std::vector<Answered>* done, std::optional<db::Trial>* pending, int* max_plan_index) {
  for (const auto& t : database.Trials(session)) {
    *max_plan_index = std::max(*max_plan_index, t.plan_index);
    if (t.phase != protocols::ToString(kind)) continue;
    // The phase index is part of the row's comparison text ("phase <i>: <parameter>").
    if (t.comparison.rfind(fmt::format("phase {}:", phase_index), 0) != 0) continue;
    if (t.status != db::kTrialCompleted) {
      *pending = t;
      continue;
    }
    const auto rs = database.Ratings(t.id);
    done->push_back({t.id, t.repetition, RatingOf(rs, kLevel), RatingOf(rs, kCorrect) > 0.5});
  }
}

struct Presented {
  bool aborted = false;    // the experimenter aborted during an interval
  bool fault = false;      // the watchdog tripped, or an interval touched nothing
  bool untouched = false;  // an interval touched nothing (the rig's sample poses?)
  bool injected = false;   // the fault was injected by the simulation (--inject-faults)
  std::string detail;
};

// Presents the trial's intervals through the one trial path (RunStimulusSide): each
// interval's model with the method's renderer in the real-time engine over the rig's device
// and actuator, with the watchdog and the writer (streams i<k>_force / i<k>_vibration). On a
// simulated rig the hand strokes each interval (the same exploration, jittered per interval,
// on the sample pose of the interval's screen side). With a UI the engine's stylus frames are
// shown (2AFC: interval 1 left, 2 right; else left). The first interval stops at a fault.
// The generator's draws (strokes, render seeds, the injected fault) come first and in a fixed
// order, so the answer drawn after the presentation does not depend on how it went.
Presented PresentIntervals(const std::vector<renderer::MaterialModel>& intervals,
                           const protocols::Method& method, const protocols::Protocol& p,
                           const db::Trial& t, const RunOptions& opt, HardwareRig& rig, Rng& rng,
                           db::TrajectoryWriter* writer, db::Database& database,
                           std::int64_t session, TrialScreen* screen, const std::string& kind,
                           double* stimulus_s) {
  Presented out;
  const std::size_t m = intervals.size();
  std::vector<sim::Stroke> strokes(m);
  std::vector<std::uint64_t> seeds(m);
  for (std::size_t k = 0; k < m; ++k) {
    strokes[k] = k == 0 ? sim::DrawStroke(rng) : sim::JitterStroke(strokes[0], rng);
    seeds[k] = rng.NextU64();
  }
  // A simulated link dropout (tests): 50 ms from 30 % into the first interval.
  const bool inject_dropout = opt.fault_rate > 0 && rng.Uniform() < opt.fault_rate;
  const double dur = p.stimulus_duration_s;
  for (std::size_t k = 0; k < m; ++k) {
    const int side = m == 2 ? static_cast<int>(k) : 0;
    StimulusSide s;
    s.model = &intervals[k];
    s.options = MethodOptions(method, seeds[k]);
    s.sample = side;
    s.stroke = strokes[k];
    s.dropout_at_s = inject_dropout && k == 0 ? 0.3 * dur : -1;
    s.stream = fmt::format("i{}", k + 1);
    s.label = fmt::format("interval {}", k + 1);
    s.stimulus = t.left;
    s.report_side = static_cast<int>(k);
    screen->phase = fmt::format("{}: interval {} of {}", kind, k + 1, m);
    const auto r = RunStimulusSide(s, rig, dur, opt, writer, database, session, t, *screen, side);
    if (r.aborted) {
      out.aborted = true;
      return out;
    }
    *stimulus_s += dur;
    if (r.fault) {
      out.fault = true;
      out.injected = inject_dropout;
      out.detail = "watchdog: " + r.detail + "; force was zeroed, trial repeated";
      return out;
    }
    if (r.untouched) {
      out.fault = out.untouched = true;
      out.detail = "nothing was touched: " + r.detail +
                   "; check the rig's sample poses (hapticlab rig show); trial repeated";
      return out;
    }
  }
  return out;
}

}  // namespace

renderer::MaterialModel WithParameter(const renderer::MaterialModel& m,
                                      const std::string& parameter, double value) {
  renderer::MaterialModel r = m;
  if (parameter == "vibration.gain") {
    for (auto& c : r.vibration.cells) c.gain *= value;
  } else if (parameter == "geometry.amplitude_scale") {
    const auto& g = *m.geometry;
    std::vector<float> h(g.data().size());
    for (std::size_t i = 0; i < h.size(); ++i) h[i] = static_cast<float>(g.data()[i] * value);
    r.geometry =
        std::make_shared<renderer::HeightMap>(g.width(), g.height(), g.pitch_m(), std::move(h));
  } else if (parameter == "contact.K") {
    r.contact.texture.K = value;
  } else if (parameter == "friction.mu_k") {
    r.friction.mu_k = value;
  } else if (parameter == "friction.mu_b_Ns_per_m") {
    r.friction.mu_b_Ns_per_m = value;
  } else {
    // The protocol parser admits only protocols::AdaptiveParameters(): a caller's bug.
    HL_REQUIRE(false, "unknown adaptive parameter '" + parameter + "'");
  }
  return r;
}

void CheckAdaptivePhases(const protocols::Protocol& p, const std::string& device, bool with_ui) {
  Diagnostics d;
  for (std::size_t i = 0; i < p.phases.size(); ++i) {
    const auto& ph = p.phases[i];
    if (!ph.adaptive) continue;
    if (device != "sim" && device != "falcon-twin")
      d.Add(p.file, ph.line, fmt::format("phase[{}].kind", i),
            "adaptive phases run on a simulated device (sim or falcon-twin) in this build "
            "(on a hardware device the participant's answers are not wired up and checked yet)");
    else if (!ph.adaptive->simulated_observer && !with_ui)
      d.Add(p.file, ph.line, fmt::format("phase[{}].simulated_observer", i),
            "missing; a simulated rig without the participant window needs the observer's true "
            "psychometric function "
            "on the varied parameter");
  }
  d.ThrowIfAny();
}

AdaptiveOutcome RunAdaptivePhases(db::Database& database, std::int64_t session,
                                  const protocols::Protocol& p,
                                  const std::map<std::string, renderer::MaterialModel>& models,
                                  std::uint64_t participant_seed, const RunOptions& opt,
                                  HardwareRig& rig, db::TrajectoryWriter* writer, int* executed) {
  AdaptiveOutcome out;
  int untouched_in_a_row = 0;
  CheckAdaptivePhases(p, opt.device, opt.ui != nullptr);
  for (std::size_t pi = 0; pi < p.phases.size(); ++pi) {
    const auto& ph = p.phases[pi];
    if (!ph.adaptive) continue;
    const AdaptiveSpec& a = *ph.adaptive;
    const auto& method = *p.FindMethod(a.method);
    const auto& base = models.at(a.material);
    const int m = psychophysics::Intervals(a.task);
    const std::uint64_t phase_seed = DeriveSeed(participant_seed, 0xADA0'0000ull + pi);
    for (;;) {
      std::vector<Answered> done;
      std::optional<db::Trial> pending;
      int max_index = -1;
      History(database, session, pi, ph.kind, &done, &pending, &max_index);
      // The next stimulus: a pure function of the recorded answers.
      int track = 0;
      double x = 0;
      if (ph.kind == PhaseKind::kStaircase) {
        std::vector<psychophysics::StaircaseTrial> h;
        for (const auto& d : done) h.push_back({d.track, d.level, d.positive});
        const auto next = psychophysics::NextTrial(a.staircase, h, phase_seed);
        if (next.done) break;
        track = next.track;
        x = next.level;
      } else {
        if (static_cast<int>(done.size()) >= a.quest_trials) break;
        std::vector<std::pair<double, bool>> h;
        for (const auto& d : done) h.emplace_back(d.level, d.positive);
        x = psychophysics::QuestPlus::Replay(a.quest, h).NextStimulus();
      }
      if (opt.stop_after_trials >= 0 && *executed >= opt.stop_after_trials) {
        database.LogEvent({.session_id = session,
                           .kind = "abort",
                           .detail = "stopped after the requested number of trials",
                           .established_by = source::CommandLine("--stop-after")});
        database.EndSession(session, "aborted");
        out.aborted = true;
        return out;
      }
      db::Trial t;
      const double value = a.reference + x;
      if (pending) {
        t = *pending;  // an interrupted or faulted trial runs again at the level the record gives
      } else {
        t = {.session_id = session,
             .plan_index = max_index + 1,
             .phase = protocols::ToString(ph.kind),
             .material = a.material,
             .comparison = fmt::format("phase {}: {}", pi, a.parameter),
             .method = a.method,
             .repetition = track,
             .left = fmt::format("virtual:{}", a.material),
             .right = fmt::format("virtual:{}", a.material)};
        t.id = database.AddTrial(t);
        ++out.added;
      }
      database.StartTrial(t.id);
      ++t.attempts;
      ++*executed;
      // The comparison's interval depends on the trial only (a repeat shows the same layout);
      // the strokes and the answer on the attempt too.
      Rng layout(DeriveSeed(phase_seed, static_cast<std::uint64_t>(t.plan_index)));
      const int comparison =
          m == 1 ? 0 : static_cast<int>(layout.Below(static_cast<std::uint64_t>(m)));
      std::vector<renderer::MaterialModel> intervals;
      for (int k = 0; k < m; ++k)
        intervals.push_back(
            WithParameter(base, a.parameter, k == comparison ? value : a.reference));
      Rng rng(DeriveSeed(participant_seed, static_cast<std::uint64_t>(t.plan_index) * 64 +
                                               static_cast<std::uint64_t>(t.attempts)));
      TrialScreen screen;
      screen.index = static_cast<int>(done.size()) + 1;
      screen.plan_number = t.plan_index + 1;  // the plan grows by one trial at a time
      screen.plan_total = t.plan_index + 1;
      screen.left = screen.right = fmt::format("virtual:{}", a.material);
      screen.method = a.method;
      screen.placement = "nothing to place: every interval is virtual";
      screen.question =
          m == 1 ? "Did you feel it?"
                 : (m == 2 ? "Which interval was stronger?" : "Which interval differed?");
      if (m == 1)
        screen.answers = {"yes", "no"};
      else
        for (int k = 0; k < m; ++k) screen.answers.push_back(std::to_string(k + 1));
      const Presented shown =
          PresentIntervals(intervals, method, p, t, opt, rig, rng, writer, database, session,
                           &screen, protocols::ToString(ph.kind), &out.stimulus_s);
      const auto abort = [&](const std::string& why, const char* by = source::kConsole) {
        database.LogEvent({.session_id = session,
                           .trial_id = t.id,
                           .kind = "abort",
                           .detail = why,
                           .established_by = by});
        database.EndSession(session, "aborted");
        out.aborted = true;
      };
      if (shown.aborted) {
        abort("the experimenter aborted in the console; 'study resume' continues with this trial");
        return out;
      }
      untouched_in_a_row = shown.untouched ? untouched_in_a_row + 1 : 0;
      if (shown.fault) {
        ++out.faults;
        database.SetTrialStatus(t.id, db::kTrialFaulted);
        database.LogEvent({.session_id = session,
                           .trial_id = t.id,
                           .kind = "device-fault",
                           .detail = shown.detail,
                           .established_by = shown.untouched
                                                 ? std::string(source::kRunner)
                                                 : source::Watchdog(opt.device, shown.injected)});
        const std::string line =
            fmt::format("{} trial {} (attempt {}) faulted: {}; runs again at the same level",
                        protocols::ToString(ph.kind), t.plan_index + 1, t.attempts, shown.detail);
        database.LogEvent({.session_id = session,
                           .trial_id = t.id,
                           .kind = "attempt-faulted",
                           .detail = line,
                           .established_by = source::kRunner});
        if (opt.warn) opt.warn(line);
        if (opt.ui)
          opt.ui->Event(fmt::format("{} trial {}: {}", protocols::ToString(ph.kind),
                                    done.size() + 1, shown.detail));
        if (untouched_in_a_row >= opt.max_untouched_trials) {
          abort(fmt::format(
                    "{} trials in a row touched nothing: the rig's sample poses are probably wrong "
                    "(hapticlab rig show / rig calibrate)",
                    untouched_in_a_row),
                source::kRunner);
          return out;
        }
        continue;  // the same trial (same level) runs again
      }
      // The answer: the participant at the window when there is one (it showed the engine's
      // stylus frames of every interval), else the simulated observer.
      sim::ObserverAnswer ans;
      double response_time_s = 0;
      if (opt.ui) {
        const auto asked = std::chrono::steady_clock::now();
        const auto choice = opt.ui->Choose(screen);
        if (!choice || *choice < 0 || *choice >= static_cast<int>(screen.answers.size())) {
          abort("the experimenter aborted; 'study resume' continues with this trial");
          return out;
        }
        response_time_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
        ans.positive = m == 1 ? *choice == 0 : *choice == comparison;
        ans.response = m == 1 ? (*choice == 0 ? 1 : 0) : *choice;
      } else {
        ans = sim::SimulatedAnswer(*a.simulated_observer, a.task, x, comparison, rng);
        response_time_s = sim::Observer::ResponseTime(rng);
      }
      database.CompleteTrial(
          t.id, {{kLevel, x, 0},
                 {kResponse, static_cast<double>(m == 1 ? ans.response : ans.response + 1),
                  response_time_s},
                 {kCorrect, ans.positive ? 1.0 : 0.0, 0},
                 {kInterval, m == 1 ? 0.0 : comparison + 1.0, 0},
                 {kPhase, static_cast<double>(pi), 0}});
      ++out.completed;
      if (opt.log)
        opt.log(fmt::format("trial {} ({} {}: {} = {:.4g}, x = {:.4g}): {}", t.plan_index + 1,
                            protocols::ToString(ph.kind), done.size() + 1, a.parameter, value, x,
                            ans.positive ? "positive" : "negative"));
    }
  }
  return out;
}

}  // namespace hapticlab::runner::internal
