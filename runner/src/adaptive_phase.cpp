#include "adaptive_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/psychophysics/quest_plus.hpp"
#include "hapticlab/psychophysics/simulated_observer.hpp"
#include "hapticlab/psychophysics/staircase.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/runner/sim_lab.hpp"

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

renderer::RenderOptions MethodRenderOptions(const protocols::Method& m, std::uint64_t seed) {
  renderer::RenderOptions o;
  o.algorithm = renderer::ParseForceAlgorithm(m.algorithm);
  o.vibration = m.vibration;
  o.hybrid_filter = m.hybrid_filter;
  o.force_rate_hz = 1000;
  o.vibration_rate_hz = 10000;
  o.stale_after_s = 1e9;  // the simulated device is never stale
  o.seed = seed;
  return o;
}

struct Presented {
  bool fault = false;
  std::string detail;
  std::vector<Interaction> shown;  // one per interval (kept for a participant window)
};

// Plays a simulated interaction's stylus path to the UI in (scaled) real time; at least one
// frame, however fast the playback.
bool Play(SessionUi& ui, const TrialScreen& screen, int side, const Interaction& in, double duration_s,
          double speed) {
  const std::size_t n = in.force.size() / 15;
  if (n == 0) return true;
  const auto t0 = std::chrono::steady_clock::now();
  double t = 0;
  do {
    const auto i = std::min(n - 1, static_cast<std::size_t>(t * in.force_rate_hz));
    const Eigen::Vector3d pos(in.force[i * 15], in.force[i * 15 + 1], in.force[i * 15 + 2]);
    if (!ui.Stimulus(screen, side, pos, duration_s - t)) return false;
    t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * speed;
  } while (t < duration_s);
  return true;
}


// Presents the trial's intervals in the simulated lab: the participant strokes each rendering
// (the same exploration, jittered, on every interval) and the interactions are recorded as
// streams i<k>_force / i<k>_vibration.
Presented PresentSim(const std::vector<renderer::MaterialModel>& intervals,
                     const protocols::Method& method, const protocols::Protocol& p,
                     const db::Trial& t, const RunOptions& opt, Rng& rng,
                     db::TrajectoryWriter* writer, double* stimulus_s) {
  Presented out;
  const Stroke first = DrawStroke(rng);
  for (std::size_t k = 0; k < intervals.size(); ++k) {
    const Stroke s = k == 0 ? first : JitterStroke(first, rng);
    Interaction in = StrokeVirtual(intervals[k], MethodRenderOptions(method, rng.NextU64()), s,
                                   p.stimulus_duration_s);
    *stimulus_s += p.stimulus_duration_s;
    if (opt.ui) out.shown.push_back(in);
    if (in.faults > 0) {
      out.fault = true;
      out.detail =
          fmt::format("renderer reported {} faulted ticks in interval {}", in.faults, k + 1);
      return out;
    }
    if (!writer || opt.record == RecordMode::kNone) continue;
    const std::string name = fmt::format("i{}", k + 1);
    auto* fs = writer->OpenStream(t.id, name + "_force", in.force_rate_hz, ForceStreamChannels());
    const std::size_t nf = in.force.size() / 15;
    for (std::size_t i = 0; i < nf; ++i)
      while (!fs->Push(static_cast<double>(i) / in.force_rate_hz, &in.force[i * 15]))
        writer->Flush();
    writer->CloseStream(fs);
    if (opt.record == RecordMode::kAll) {
      auto* vs = writer->OpenStream(t.id, name + "_vibration", in.vibration_rate_hz,
                                    VibrationStreamChannels());
      for (std::size_t i = 0; i < in.vibration.size(); ++i)
        while (!vs->Push(static_cast<double>(i) / in.vibration_rate_hz, &in.vibration[i]))
          writer->Flush();
      writer->CloseStream(vs);
    }
  }
  if (opt.fault_rate > 0 && rng.Uniform() < opt.fault_rate) {
    out.fault = true;
    out.detail = "simulated device fault (injected): force driven to zero, trial repeated";
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
    throw std::invalid_argument("unknown adaptive parameter '" + parameter + "'");
  }
  return r;
}

void CheckAdaptivePhases(const protocols::Protocol& p, const std::string& device, bool with_ui) {
  Diagnostics d;
  for (std::size_t i = 0; i < p.phases.size(); ++i) {
    const auto& ph = p.phases[i];
    if (!ph.adaptive) continue;
    if (device != "sim")
      d.Add(p.file, ph.line, fmt::format("phase[{}].kind", i),
            "adaptive phases run with --device sim in this build (hardware presentation of the "
            "intervals is not implemented yet)");
    else if (!ph.adaptive->simulated_observer && !with_ui)
      d.Add(p.file, ph.line, fmt::format("phase[{}].simulated_observer", i),
            "missing; --device sim without --ui needs the observer's true psychometric function on "
            "the varied parameter");
  }
  d.ThrowIfAny();
}

AdaptiveOutcome RunAdaptivePhases(db::Database& database, std::int64_t session,
                                  const protocols::Protocol& p,
                                  const std::map<std::string, renderer::MaterialModel>& models,
                                  std::uint64_t participant_seed, const RunOptions& opt,
                                  db::TrajectoryWriter* writer, int* executed) {
  AdaptiveOutcome out;
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
                           .detail = "stopped after the requested number of trials"});
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
      const Presented shown =
          PresentSim(intervals, method, p, t, opt, rng, writer, &out.stimulus_s);
      if (shown.fault) {
        ++out.faults;
        database.SetTrialStatus(t.id, db::kTrialFaulted);
        database.LogEvent({.session_id = session,
                           .trial_id = t.id,
                           .kind = "device-fault",
                           .detail = shown.detail});
        continue;  // the same trial (same level) runs again
      }
      // The answer: the participant at the window when there is one (the simulated strokes
      // are what it shows), else the simulated observer.
      psychophysics::ObserverAnswer ans;
      double response_time_s = 0;
      if (opt.ui) {
        TrialScreen screen;
        screen.index = static_cast<int>(done.size()) + 1;
        screen.left = screen.right = fmt::format("virtual:{}", a.material);
        screen.method = a.method;
        screen.placement = "nothing to place: every interval is virtual";
        screen.question = m == 1 ? "Did you feel it?"
                                 : (m == 2 ? "Which interval was stronger?" : "Which interval differed?");
        if (m == 1) screen.answers = {"yes", "no"};
        else
          for (int k = 0; k < m; ++k) screen.answers.push_back(std::to_string(k + 1));
        bool go_on = true;
        for (int k = 0; k < m && go_on; ++k) {
          screen.phase = fmt::format("{}: interval {} of {}", protocols::ToString(ph.kind), k + 1, m);
          go_on = Play(*opt.ui, screen, m == 2 ? k : 0, shown.shown[static_cast<std::size_t>(k)],
                       p.stimulus_duration_s, opt.ui_playback_speed);
        }
        const auto asked = std::chrono::steady_clock::now();
        const auto choice = go_on ? opt.ui->Choose(screen) : std::nullopt;
        if (!choice || *choice < 0 || *choice >= static_cast<int>(screen.answers.size())) {
          database.LogEvent({.session_id = session,
                             .trial_id = t.id,
                             .kind = "abort",
                             .detail = "the experimenter aborted; 'study resume' continues with this trial"});
          database.EndSession(session, "aborted");
          out.aborted = true;
          return out;
        }
        response_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
        ans.positive = m == 1 ? *choice == 0 : *choice == comparison;
        ans.response = m == 1 ? (*choice == 0 ? 1 : 0) : *choice;
      } else {
        ans = psychophysics::SimulatedAnswer(*a.simulated_observer, a.task, x, comparison, rng);
        response_time_s = Observer::ResponseTime(rng);
      }
      database.CompleteTrial(
          t.id, {{kLevel, x, 0},
                 {kResponse, static_cast<double>(m == 1 ? ans.response : ans.response + 1), response_time_s},
                 {kCorrect, ans.positive ? 1.0 : 0.0, 0},
                 {kInterval, m == 1 ? 0.0 : comparison + 1.0, 0},
                 {kPhase, static_cast<double>(pi), 0}});
      ++out.completed;
      if (opt.log)
        opt.log(fmt::format("{} trial {} ({} = {:.4g}, x = {:.4g}): {}",
                            protocols::ToString(ph.kind), done.size() + 1, a.parameter, value, x,
                            ans.positive ? "positive" : "negative"));
    }
  }
  return out;
}

}  // namespace hapticlab::runner::internal
