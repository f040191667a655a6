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

TrialStimuli ParseStimuli(const db::Trial& t) {
  TrialStimuli s{ParseStimulus(t.left), std::nullopt};
  if (!t.right.empty()) s.right = ParseStimulus(t.right);
  return s;
}

TrialScreen ScreenOf(const protocols::Protocol& p, const db::Trial& t, const TrialStimuli& stimuli,
                     int index, int total) {
  TrialScreen s;
  s.index = index;
  s.total = total;
  s.phase = NameOf(kPhaseKindNames, t.phase);
  s.left = t.left;
  s.right = t.right;
  s.method = t.method;
  s.plan_number = t.plan_index + 1;
  // What the experimenter places: "left = real Denim, right = virtual" (the virtual side's
  // material is not placed, so it is not named).
  auto what = [&s](const Stimulus& st) {
    s.real_sample = s.real_sample || st.real;
    return st.real ? "real " + st.id : std::string("virtual");
  };
  s.placement = !stimuli.right ? fmt::format("left = {}, right = nothing", what(stimuli.left))
                               : fmt::format("left = {}, right = {}", what(stimuli.left),
                                             what(*stimuli.right));
  s.sides = stimuli.right ? 2 : 1;
  s.stimulus_s = p.stimulus_duration_s;
  for (const auto& ph : p.phases)
    if (IsTraining(t.phase) && ph.kind == PhaseKind::kTraining) s.stimulus_s = ph.duration_s;
  s.break_s = p.break_duration_s;
  s.criteria = p.criteria;
  s.scale_min = p.scale_min;
  s.scale_max = p.scale_max;
  return s;
}

namespace {

// Training (ch. V.2.1): each virtual sample in turn, explored freely for the phase's
// duration, not rated. A participant who learns nothing from it (a simulated one without
// screens) gets the trial recorded without rendering it.
Outcome ExecuteTraining(const Lab& lab, const db::Trial& t, const TrialStimuli& stimuli,
                        std::uint64_t trial_seed, const TrialContext& c,
                        const TrialScreen& screen) {
  const auto& p = *lab.protocol;
  Outcome out;
  if (!c.participant.RendersTraining()) return out;
  Rng rng(trial_seed);
  const protocols::Phase* phase = nullptr;
  for (const auto& ph : p.phases)
    if (ph.kind == PhaseKind::kTraining) phase = &ph;
  StimulusSide s;
  s.model = &lab.models.at(stimuli.left.id);
  s.material = stimuli.left.id;
  const auto* method = p.FindMethod(t.method);
  if (!stimuli.left.real && method) s.options = MethodOptions(*method, DeriveSeed(trial_seed, 0));
  s.real = stimuli.left.real || !method;  // plans from before virtual training: the real sample
  s.sample = 0;
  s.stream = "left";
  s.label = "training sample";
  s.stimulus = t.left;
  c.participant.DrawExploration(rng, 1, nullptr);
  const double train_s = phase ? phase->duration_s : p.stimulus_duration_s;
  const auto r = RunStimulusSide(s, c, rng, train_s, t, screen, 0);
  out.aborted = r.aborted;
  out.stimulus_s = train_s;
  // A fault while training is logged (the watchdog zeroed the force) but the unrated trial
  // is not repeated: a device that keeps faulting is caught by the rated trials.
  if (r.fault) {
    c.database.LogEvent(
        {.session_id = c.session,
         .trial_id = t.id,
         .kind = db::EventKind::kDeviceFault,
         .detail = "watchdog: " + r.detail + "; force was zeroed; training trial not repeated",
         .established_by = source::Watchdog(c.opt.device, false)});
    if (c.opt.ui) c.opt.ui->Event(fmt::format("training trial {}: {}", t.plan_index + 1, r.detail));
  }
  return out;
}

}  // namespace

Outcome ExecuteTrial(const Lab& lab, const db::Trial& t, const TrialStimuli& stimuli,
                     std::uint64_t participant_seed, const TrialContext& c,
                     const TrialScreen& screen) {
  const auto& p = *lab.protocol;
  const std::uint64_t trial_seed =
      DeriveSeed(participant_seed, static_cast<std::uint64_t>(t.plan_index) * 64 +
                                       static_cast<std::uint64_t>(t.attempts));
  if (IsTraining(t.phase)) return ExecuteTraining(lab, t, stimuli, trial_seed, c, screen);
  Outcome out;
  Rng rng(trial_seed);
  const double dur = p.stimulus_duration_s;
  // The participant's exploration: one, the same with ~10 % variation on the other side.
  c.participant.DrawExploration(rng, 2, nullptr);
  const bool inject_dropout = c.participant.DrawDropout(rng, c.opt.fault_rate, dur);
  std::array<sim::Features, 2> felt{};
  std::vector<std::string> faults, untouched;
  for (int side = 0; side < 2; ++side) {
    const Stimulus& stim = side == 0 ? stimuli.left : *stimuli.right;
    StimulusSide s;
    s.model = &lab.models.at(stim.id);
    s.material = stim.id;
    s.real = stim.real;
    if (!s.real)
      s.options = MethodOptions(*p.FindMethod(t.method),
                                DeriveSeed(trial_seed, static_cast<std::uint64_t>(side)));
    s.sample = side;
    s.stream = side == 0 ? "left" : "right";
    s.label = s.stream + " side";
    s.stimulus = side == 0 ? t.left : t.right;
    s.report_side = side;
    const auto r = RunStimulusSide(s, c, rng, dur, t, screen, side);
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
  auto ratings = c.participant.Rate(t, screen, felt, rng);
  out.aborted = !ratings;
  if (ratings) out.ratings = std::move(*ratings);
  return out;
}

}  // namespace hapticlab::runner::internal
