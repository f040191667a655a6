#include "hapticlab/renderer/hybrid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {

HybridRenderer::HybridRenderer(const MaterialModel& m, const RenderOptions& o)
    : options_(o),
      cutoff_hz_(m.hybrid_cutoff_hz),
      force_(m, o.algorithm, 0.5 * o.device_max_stiffness_N_per_m),
      interp_(m.vibration),
      synth_(o.seed) {
  HL_REQUIRE(o.force_rate_hz > 0 && o.vibration_rate_hz > 0, "loop rates must be positive");
  HL_REQUIRE(o.max_force_N > 0, "max_force_N must be positive");
  const std::string source = m.source_path.empty() ? m.name : m.source_path;
  filter_on_ = o.hybrid_filter && cutoff_hz_ > 0;
  if (filter_on_) {
    const double nyquist_hz = 0.5 * std::min(o.force_rate_hz, o.vibration_rate_hz);
    if (!(cutoff_hz_ < nyquist_hz))
      throw InputError(source, 0, "hybrid_cutoff_hz",
                       "below both loops' Nyquist rate (" + std::to_string(nyquist_hz) + " Hz)");
    const auto lp = BiquadCoeffs::ButterworthLowPass(cutoff_hz_, o.force_rate_hz);
    for (auto& f : force_lp_) f.SetCoeffs(lp);
    vib_hp_.SetCoeffs(BiquadCoeffs::ButterworthHighPass(cutoff_hz_, o.vibration_rate_hz));
  }
  if (o.vibration && m.neural) {
    if (m.neural->sample_rate_hz > o.vibration_rate_hz)
      throw InputError(
          m.neural_file.empty() ? source : m.neural_file, 0, "sample_rate_hz",
          "at most the vibration loop's rate (" + std::to_string(o.vibration_rate_hz) + " Hz)");
    neural_ = std::make_unique<NeuralSynth>(m.neural, o.seed);
    step_ = m.neural->sample_rate_hz / o.vibration_rate_hz;
  } else if (o.vibration && !m.vibration.empty()) {
    if (m.vibration.sample_rate_hz > o.vibration_rate_hz)
      throw InputError(
          source, 0, "vibration.sample_rate_hz",
          "at most the vibration loop's rate (" + std::to_string(o.vibration_rate_hz) + " Hz)");
    step_ = m.vibration.sample_rate_hz / o.vibration_rate_hz;
  }
  // An integer rate ratio (2 kHz, 1 kHz models at a 10 kHz loop...) upsamples band-limited.
  const double ratio = 1.0 / step_;
  const double rounded = std::round(ratio);
  if (std::abs(ratio - rounded) <= 1e-9 * ratio)
    up_ = PolyphaseUpsampler(static_cast<int>(rounded), kUpsampleTapsPerPhase);
  else
    up_ = PolyphaseUpsampler();  // factor 1, unused: linear interpolation instead
  upsample_ = std::abs(ratio - rounded) <= 1e-9 * ratio;
}

void HybridRenderer::Fault(std::atomic<std::uint64_t>& counter) noexcept {
  counter.fetch_add(1, std::memory_order_relaxed);
  force_.Reset();
  for (auto& f : force_lp_) f.Reset();
  ArFilter& slot = filter_box_.WriteSlot();
  slot.active = false;
  filter_box_.Publish();
}

ForceCommand HybridRenderer::ForceTick(const DeviceSample& in, double now_s) noexcept {
  counters_.force_ticks.fetch_add(1, std::memory_order_relaxed);
  ForceCommand cmd;
  if (vib_fault_pending_.exchange(false, std::memory_order_acq_rel)) {
    cmd.fault = cmd.vibration_fault = true;
    Fault(counters_.vibration_faults);
    return cmd;
  }
  const bool finite = in.state.p_m.allFinite() && in.state.v_mps.allFinite() &&
                      std::isfinite(in.t_s) && std::isfinite(now_s) &&
                      (!in.has_normal_force || std::isfinite(in.normal_force_N));
  if (!finite) {
    cmd.fault = true;
    Fault(counters_.nan_faults);
    return cmd;
  }
  if (now_s - in.t_s > options_.stale_after_s) {
    cmd.fault = true;
    Fault(counters_.stale_faults);
    return cmd;
  }
  cmd.raw = force_.Step(in.state);
  Eigen::Vector3d f = cmd.raw.force_N;
  if (filter_on_)
    for (int i = 0; i < 3; ++i) f[i] = force_lp_[static_cast<std::size_t>(i)].Step(f[i]);
  if (!f.allFinite()) {
    cmd.fault = true;
    Fault(counters_.nan_faults);
    return cmd;
  }
  const double mag = f.norm();
  if (mag > options_.max_force_N) {
    f *= options_.max_force_N / mag;
    cmd.saturated = true;
    counters_.saturations.fetch_add(1, std::memory_order_relaxed);
  }
  cmd.force_N = f;
  // Publish the vibration filter for the current speed and normal force: the measured one
  // when the device reports it (in contact while it presses), else the rendered one.
  const bool measured = in.has_normal_force;
  const double vib_force_N = measured ? std::max(0.0, in.normal_force_N) : cmd.raw.normal_force_N;
  const bool vib_contact = measured ? in.normal_force_N > 0 : cmd.raw.in_contact;
  ArFilter& slot = filter_box_.WriteSlot();
  if (options_.vibration) {
    interp_.Interpolate(cmd.raw.tangential_speed_mps, vib_force_N, vib_contact, &slot);
    if (neural_) slot.active = vib_contact;  // the neural synth applies its own minimum speed
  } else {
    slot.active = false;
  }
  slot.speed_mps = cmd.raw.tangential_speed_mps;
  slot.force_N = vib_force_N;
  filter_box_.Publish();
  return cmd;
}

double HybridRenderer::ModelSample(const ArFilter& f) noexcept {
  if (vib_muted_.load(std::memory_order_relaxed)) return 0;
  const double x = neural_ ? neural_->Step(f.speed_mps, f.force_N, f.active) : synth_.Step(f);
  // The AR bank's filters are stable by construction (LSF interpolation): only a non-finite
  // sample is a fault there; the neural synthesizer also mutes itself beyond its level.
  if (std::isfinite(x) && !(neural_ && neural_->runaway())) return x;
  vib_muted_.store(true, std::memory_order_release);
  vib_fault_pending_.store(true, std::memory_order_release);
  return 0;
}

double HybridRenderer::VibrationTick() noexcept {
  counters_.vibration_ticks.fetch_add(1, std::memory_order_relaxed);
  const ArFilter& f = filter_box_.Read();
  // Run the model at its rate; upsample band-limited (integer ratio) or linearly.
  double a;
  if (upsample_) {
    if (up_phase_ == 0) up_.Push(ModelSample(f));
    a = up_.Output(up_phase_);
    up_phase_ = up_phase_ + 1 == up_.factor() ? 0 : up_phase_ + 1;
  } else {
    phase_ += step_;
    while (phase_ >= 1.0) {
      phase_ -= 1.0;
      prev_ = next_;
      next_ = ModelSample(f);
    }
    a = prev_ + (next_ - prev_) * phase_;
  }
  const bool muted = vib_muted_.load(std::memory_order_relaxed);
  if (!f.active || muted) {
    // Clear the model's state now (both calls do nothing when it is already clear; a muted
    // model is not run again).
    if (!muted && neural_)
      neural_->Step(0, 0, false);
    else if (!muted)
      synth_.StepWith(f, 0.0);
    prev_ = next_ = 0;
    up_.Reset();
    up_phase_ = 0;
    a = 0;
  }
  if (filter_on_) a = vib_hp_.Step(a);
  return std::isfinite(a) ? a : 0.0;
}

}  // namespace hapticlab::renderer
