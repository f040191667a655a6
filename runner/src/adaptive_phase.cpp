#include "adaptive_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/psychophysics/quest_plus.hpp"
#include "hapticlab/psychophysics/staircase.hpp"
#include "hapticlab/runner/audit.hpp"
#include "participant.hpp"
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
    if (t.phase != kind) continue;
    // The phase index is part of the row's comparison text ("phase <i>: <parameter>").
    if (t.comparison.rfind(fmt::format("phase {}:", phase_index), 0) != 0) continue;
    if (t.status != db::TrialStatus::kCompleted) {
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
// and actuator, with the watchdog and the writer (streams i<k>_force / i<k>_vibration), the
// participant holding the stylus (the same exploration, varied per interval, on the sample
// pose of the interval's screen side). With a UI the engine's stylus frames are shown (2AFC:
// interval 1 left, 2 right; else left). The first interval stops at a fault. The generator's
// draws (explorations, render seeds, the injected fault) come first and in a fixed order, so
// the answer drawn after the presentation does not depend on how it went.
Presented PresentIntervals(const std::vector<renderer::MaterialModel>& intervals,
                           const protocols::Method& method, const protocols::Protocol& p,
                           const db::Trial& t, const TrialContext& c, Rng& rng, TrialScreen* screen,
                           const std::string& kind, double* stimulus_s) {
  Presented out;
  const std::size_t m = intervals.size();
  std::vector<std::uint64_t> seeds;
  const double dur = p.stimulus_duration_s;
  c.participant.DrawExploration(rng, static_cast<int>(m), &seeds);
  // A link dropout (fault injection in tests): 50 ms from 30 % into the first interval.
  const bool inject_dropout = c.participant.DrawDropout(rng, c.opt.fault_rate, dur);
  for (std::size_t k = 0; k < m; ++k) {
    const int side = m == 2 ? static_cast<int>(k) : 0;
    StimulusSide s;
    s.model = &intervals[k];
    s.options = MethodOptions(method, seeds[k]);
    s.material = t.material;
    s.sample = side;
    s.stream = fmt::format("i{}", k + 1);
    s.label = fmt::format("interval {}", k + 1);
    s.stimulus = t.left;
    s.report_side = static_cast<int>(k);
    screen->phase = fmt::format("{}: interval {} of {}", kind, k + 1, m);
    const auto r = RunStimulusSide(s, c, rng, dur, t, *screen, side);
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

namespace {

// The next level of an adaptive phase: a pure function of the recorded answers; nullopt when
// the phase is done.
struct Level {
  int track = 0;
  double x = 0;  // comparison - reference [parameter unit]
};
std::optional<Level> NextLevel(const protocols::Phase& ph, const std::vector<Answered>& done,
                               std::uint64_t phase_seed) {
  const AdaptiveSpec& a = *ph.adaptive;
  if (ph.kind == PhaseKind::kStaircase) {
    std::vector<psychophysics::StaircaseTrial> h;
    for (const auto& d : done) h.push_back({d.track, d.level, d.positive});
    const auto next = psychophysics::NextTrial(a.staircase, h, phase_seed);
    if (next.done) return std::nullopt;
    return Level{next.track, next.level};
  }
  if (static_cast<int>(done.size()) >= a.quest_trials) return std::nullopt;
  std::vector<std::pair<double, bool>> h;
  for (const auto& d : done) h.emplace_back(d.level, d.positive);
  return Level{0, psychophysics::QuestPlus::Replay(a.quest, h).NextStimulus()};
}

// What the participant sees of adaptive trial `t` (the `number`-th of its phase).
TrialScreen AdaptiveScreen(const AdaptiveSpec& a, const db::Trial& t, int number, int m) {
  TrialScreen screen;
  screen.index = number;
  screen.plan_number = t.plan_index + 1;  // the plan grows by one trial at a time
  screen.plan_total = t.plan_index + 1;
  screen.left = screen.right = fmt::format("virtual:{}", a.material);
  screen.method = a.method;
  screen.placement = "nothing to place: every interval is virtual";
  screen.question = m == 1   ? "Did you feel it?"
                    : m == 2 ? "Which interval was stronger?"
                             : "Which interval differed?";
  if (m == 1)
    screen.answers = {"yes", "no"};
  else
    for (int k = 0; k < m; ++k) screen.answers.push_back(std::to_string(k + 1));
  return screen;
}

// Ends the session as aborted, with `why` as an 'abort' event of trial `trial_id` (if any).
void AbortSession(const TrialContext& c, std::optional<std::int64_t> trial_id,
                  const std::string& why, const std::string& by) {
  c.database.LogEvent({.session_id = c.session,
                       .trial_id = trial_id,
                       .kind = db::EventKind::kAbort,
                       .detail = why,
                       .established_by = by});
  c.database.EndSession(c.session, db::SessionStatus::kAborted);
}

// A faulted attempt of adaptive trial `t`: its cause and the re-run as events, on the log
// and the console.
void RecordFault(const TrialContext& c, const protocols::Phase& ph, const db::Trial& t,
                 const Presented& shown, std::size_t number) {
  c.database.SetTrialStatus(t.id, db::TrialStatus::kFaulted);
  c.database.LogEvent({.session_id = c.session,
                       .trial_id = t.id,
                       .kind = db::EventKind::kDeviceFault,
                       .detail = shown.detail,
                       .established_by = shown.untouched
                                             ? std::string(source::kRunner)
                                             : source::Watchdog(c.opt.device, shown.injected)});
  const std::string line =
      fmt::format("{} trial {} (attempt {}) faulted: {}; runs again at the same level",
                  protocols::ToString(ph.kind), t.plan_index + 1, t.attempts, shown.detail);
  c.database.LogEvent({.session_id = c.session,
                       .trial_id = t.id,
                       .kind = db::EventKind::kAttemptFaulted,
                       .detail = line,
                       .established_by = source::kRunner});
  if (c.opt.warn) c.opt.warn(line);
  if (c.opt.ui)
    c.opt.ui->Event(
        fmt::format("{} trial {}: {}", protocols::ToString(ph.kind), number, shown.detail));
}

// The trial row to run at level `level` of phase `pi`: the pending one (interrupted or
// faulted: it runs again at the level the record gives), else a new row.
db::Trial TrialToRun(const TrialContext& c, const AdaptiveSpec& a, const protocols::Phase& ph,
                     std::size_t pi, const Level& level, const std::optional<db::Trial>& pending,
                     int max_index, AdaptiveOutcome* out) {
  if (pending) return *pending;
  db::Trial t{.session_id = c.session,
              .plan_index = max_index + 1,
              .phase = ph.kind,
              .material = a.material,
              .comparison = fmt::format("phase {}: {}", pi, a.parameter),
              .method = a.method,
              .repetition = level.track,
              .left = fmt::format("virtual:{}", a.material),
              .right = fmt::format("virtual:{}", a.material)};
  t.id = c.database.AddTrial(t);
  ++out->added;
  return t;
}

// Runs adaptive phase `pi` to its end. False: the session was aborted (and ended).
bool RunPhase(const protocols::Protocol& p, std::size_t pi, const renderer::MaterialModel& base,
              std::uint64_t participant_seed, const TrialContext& c, int* executed,
              int* untouched_in_a_row, AdaptiveOutcome* out) {
  const auto& ph = p.phases[pi];
  const AdaptiveSpec& a = *ph.adaptive;
  const auto& method = *p.FindMethod(a.method);
  const int m = psychophysics::Intervals(a.task);
  const std::uint64_t phase_seed = DeriveSeed(participant_seed, 0xADA0'0000ull + pi);
  for (;;) {
    std::vector<Answered> done;
    std::optional<db::Trial> pending;
    int max_index = -1;
    History(c.database, c.session, pi, ph.kind, &done, &pending, &max_index);
    const auto level = NextLevel(ph, done, phase_seed);
    if (!level) return true;
    if (c.opt.stop_after_trials >= 0 && *executed >= c.opt.stop_after_trials) {
      AbortSession(c, std::nullopt, "stopped after the requested number of trials",
                   source::CommandLine("--stop-after"));
      return false;
    }
    db::Trial t = TrialToRun(c, a, ph, pi, *level, pending, max_index, out);
    const double x = level->x, value = a.reference + x;
    c.database.StartTrial(t.id);
    ++t.attempts;
    ++*executed;
    // The comparison's interval depends on the trial only (a repeat shows the same layout);
    // the explorations and the answer on the attempt too.
    Rng layout(DeriveSeed(phase_seed, static_cast<std::uint64_t>(t.plan_index)));
    const int comparison =
        m == 1 ? 0 : static_cast<int>(layout.Below(static_cast<std::uint64_t>(m)));
    std::vector<renderer::MaterialModel> intervals;
    for (int k = 0; k < m; ++k)
      intervals.push_back(WithParameter(base, a.parameter, k == comparison ? value : a.reference));
    Rng rng(DeriveSeed(participant_seed, static_cast<std::uint64_t>(t.plan_index) * 64 +
                                             static_cast<std::uint64_t>(t.attempts)));
    TrialScreen screen = AdaptiveScreen(a, t, static_cast<int>(done.size()) + 1, m);
    const Presented shown = PresentIntervals(intervals, method, p, t, c, rng, &screen,
                                             protocols::ToString(ph.kind), &out->stimulus_s);
    if (shown.aborted) {
      AbortSession(c, t.id,
                   "the experimenter aborted in the console; 'study resume' continues with this "
                   "trial",
                   source::kConsole);
      return false;
    }
    *untouched_in_a_row = shown.untouched ? *untouched_in_a_row + 1 : 0;
    if (shown.fault) {
      ++out->faults;
      RecordFault(c, ph, t, shown, done.size() + 1);
      if (*untouched_in_a_row >= c.opt.max_untouched_trials) {
        AbortSession(c, t.id,
                     fmt::format("{} trials in a row touched nothing: the rig's sample poses are "
                                 "probably wrong (hapticlab rig show / rig calibrate)",
                                 *untouched_in_a_row),
                     source::kRunner);
        return false;
      }
      continue;  // the same trial (same level) runs again
    }
    // The answer: the participant's (Participant::Answer).
    const auto ans = c.participant.Answer(a, x, comparison, screen, rng);
    if (!ans) {
      AbortSession(c, t.id, "the experimenter aborted; 'study resume' continues with this trial",
                   source::kConsole);
      return false;
    }
    c.database.CompleteTrial(
        t.id, {{kLevel, x, 0},
               {kResponse, static_cast<double>(m == 1 ? ans->response : ans->response + 1),
                ans->response_time_s},
               {kCorrect, ans->positive ? 1.0 : 0.0, 0},
               {kInterval, m == 1 ? 0.0 : comparison + 1.0, 0},
               {kPhase, static_cast<double>(pi), 0}});
    ++out->completed;
    if (c.opt.log)
      c.opt.log(fmt::format("trial {} ({} {}: {} = {:.4g}, x = {:.4g}): {}", t.plan_index + 1,
                            protocols::ToString(ph.kind), done.size() + 1, a.parameter, value, x,
                            ans->positive ? "positive" : "negative"));
  }
}

}  // namespace

AdaptiveOutcome RunAdaptivePhases(const protocols::Protocol& p,
                                  const std::map<std::string, renderer::MaterialModel>& models,
                                  std::uint64_t participant_seed, const TrialContext& c,
                                  int* executed) {
  AdaptiveOutcome out;
  int untouched_in_a_row = 0;
  CheckAdaptivePhases(p, c.opt.device, c.opt.ui != nullptr);
  for (std::size_t pi = 0; pi < p.phases.size(); ++pi) {
    const auto& ph = p.phases[pi];
    if (!ph.adaptive) continue;
    if (!RunPhase(p, pi, models.at(ph.adaptive->material), participant_seed, c, executed,
                  &untouched_in_a_row, &out)) {
      out.aborted = true;
      return out;
    }
  }
  return out;
}

}  // namespace hapticlab::runner::internal
