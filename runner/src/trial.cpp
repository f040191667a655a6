#include "trial.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/runner/audit.hpp"
#include "stimulus_side.hpp"

namespace hapticlab::runner::internal {

using protocols::PhaseKind;
using sim::Observer;

namespace {

// The participant's ratings from the UI, clamped to the scale, with the response time from
// the rating screen's appearance; false when the experimenter aborted.
bool RateInUi(SessionUi& ui, const TrialScreen& screen, const protocols::Protocol& p,
              const std::string& source, std::vector<db::Rating>* out) {
  const auto shown = std::chrono::steady_clock::now();
  const auto r = ui.Rate(screen);
  if (!r || r->size() != p.criteria.size()) return false;
  const double rt = std::chrono::duration<double>(std::chrono::steady_clock::now() - shown).count();
  for (std::size_t i = 0; i < p.criteria.size(); ++i)
    out->push_back({p.criteria[i], ScaleValue((*r)[i], p.scale_min, p.scale_max), rt, source});
  return true;
}

}  // namespace

}  // namespace hapticlab::runner::internal

namespace hapticlab::runner {

double ScaleValue(double v, double lo, double hi) {
  if (!std::isfinite(v) || !(hi > lo)) return std::clamp(v, lo, hi);
  // The step: the largest power of ten giving the scale at least 100 steps (1 on 0..100).
  // A decimal step is applied as a division by an exact integer, so the stored value is
  // the double nearest the decimal (0.37, not 0.37000000000000005).
  const int k = static_cast<int>(std::floor(std::log10((hi - lo) / 100)));
  double snapped;
  if (k >= 0) {
    const double step = std::pow(10.0, k);
    snapped = lo + std::round((v - lo) / step) * step;
  } else {
    const double per_unit = std::pow(10.0, -k);
    snapped = std::round(v * per_unit) / per_unit;
  }
  return std::clamp(snapped, lo, hi);
}

}  // namespace hapticlab::runner

namespace hapticlab::runner::internal {

TrialScreen ScreenOf(const protocols::Protocol& p, const db::Trial& t, int index, int total) {
  TrialScreen s;
  s.index = index;
  s.total = total;
  s.phase = t.phase;
  s.left = t.left;
  s.right = t.right;
  s.method = t.method;
  s.plan_number = t.plan_index + 1;
  // What the experimenter places: "left = real Denim, right = virtual" (the virtual side's
  // material is not placed, so it is not named).
  auto what = [&s](const std::string& stim) {
    const Stimulus st = ParseStimulus(stim);
    s.real_sample = s.real_sample || st.real;
    return st.real ? "real " + st.id : std::string("virtual");
  };
  s.placement = t.right.empty() ? fmt::format("left = {}, right = nothing", what(t.left))
                                : fmt::format("left = {}, right = {}", what(t.left), what(t.right));
  s.sides = t.right.empty() ? 1 : 2;
  s.stimulus_s = p.stimulus_duration_s;
  for (const auto& ph : p.phases)
    if (t.phase == "training" && ph.kind == PhaseKind::kTraining) s.stimulus_s = ph.duration_s;
  s.break_s = p.break_duration_s;
  s.criteria = p.criteria;
  s.scale_min = p.scale_min;
  s.scale_max = p.scale_max;
  return s;
}

Outcome ExecuteTrial(const Lab& lab, const Observer& observer, const db::Trial& t,
                     std::uint64_t participant_seed, const RunOptions& opt, HardwareRig& rig,
                     db::TrajectoryWriter* writer, const TrialScreen& screen,
                     db::Database& database, std::int64_t session) {
  const auto& p = *lab.protocol;
  Outcome out;
  const std::uint64_t trial_seed =
      DeriveSeed(participant_seed, static_cast<std::uint64_t>(t.plan_index) * 64 +
                                       static_cast<std::uint64_t>(t.attempts));
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
    const auto [real, id] = ParseStimulus(t.left);
    internal::StimulusSide s;
    s.model = &lab.models.at(id);
    s.real = real;  // plans from before virtual training: the real sample
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
    const auto r =
        internal::RunStimulusSide(s, rig, train_s, opt, writer, database, session, t, screen, 0);
    out.aborted = r.aborted;
    out.stimulus_s = train_s;
    // A fault while training is logged (the watchdog zeroed the force) but the unrated trial
    // is not repeated: a device that keeps faulting is caught by the rated trials.
    if (r.fault) {
      database.LogEvent(
          {.session_id = session,
           .trial_id = t.id,
           .kind = "device-fault",
           .detail = "watchdog: " + r.detail + "; force was zeroed; training trial not repeated",
           .established_by = source::Watchdog(opt.device, false)});
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
    const auto [real, id] = ParseStimulus(stim);
    internal::StimulusSide s;
    s.model = &lab.models.at(id);
    s.real = real;
    if (!s.real)
      s.options = internal::MethodOptions(*p.FindMethod(t.method),
                                          DeriveSeed(trial_seed, static_cast<std::uint64_t>(side)));
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
    const auto r =
        internal::RunStimulusSide(s, rig, dur, opt, writer, database, session, t, screen, side);
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
    out.injected = inject_dropout;
    out.fault_detail = "watchdog: " + fmt::format("{}", fmt::join(faults, "; ")) +
                       "; force was zeroed, trial re-queued";
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
    FeltTrial ft{.plan_index = t.plan_index,
                 .phase = t.phase,
                 .material = t.material,
                 .comparison = t.comparison,
                 .method = t.method,
                 .repetition = t.repetition,
                 .distances = {},
                 .felt = felt};
    for (const auto& c : p.criteria) ft.distances.push_back(observer.Distance(c, felt[0], felt[1]));
    opt.on_felt(ft);
  }
  for (const auto& c : p.criteria)
    out.ratings.push_back(
        {c, observer.Rate(c, t.material, t.method, felt[0], felt[1], p.scale_min, p.scale_max, rng),
         Observer::ResponseTime(rng), db::kRaterSimulated});
  return out;
}

}  // namespace hapticlab::runner::internal
