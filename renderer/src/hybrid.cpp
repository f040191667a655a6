#include "hapticlab/renderer/hybrid.hpp"

#include <cmath>
#include <stdexcept>

namespace hapticlab::renderer {

HybridRenderer::HybridRenderer(const MaterialModel& m, const RenderOptions& o)
    : options_(o),
      cutoff_hz_(m.hybrid_cutoff_hz),
      force_(m, o.algorithm, 0.5 * o.device_max_stiffness_N_per_m),
      interp_(m.vibration),
      synth_(o.seed) {
  if (!(o.force_rate_hz > 0) || !(o.vibration_rate_hz > 0))
    throw std::invalid_argument("loop rates must be positive");
  if (!(o.max_force_N > 0)) throw std::invalid_argument("max_force_N must be positive");
  if (o.hybrid_filter) {
    const auto lp = BiquadCoeffs::ButterworthLowPass(cutoff_hz_, o.force_rate_hz);
    for (auto& f : force_lp_) f.SetCoeffs(lp);
    vib_hp_.SetCoeffs(BiquadCoeffs::ButterworthHighPass(cutoff_hz_, o.vibration_rate_hz));
  }
  if (o.vibration && m.neural) {
    if (m.neural->sample_rate_hz > o.vibration_rate_hz)
      throw std::invalid_argument("the neural model's rate exceeds the vibration loop's rate");
    neural_ = std::make_unique<NeuralSynth>(m.neural, o.seed);
    step_ = m.neural->sample_rate_hz / o.vibration_rate_hz;
  } else if (o.vibration && !m.vibration.empty()) {
    if (m.vibration.sample_rate_hz > o.vibration_rate_hz)
      throw std::invalid_argument("the vibration bank's rate exceeds the vibration loop's rate");
    step_ = m.vibration.sample_rate_hz / o.vibration_rate_hz;
  }
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
  const bool finite = in.state.p_m.allFinite() && in.state.v_mps.allFinite() &&
                      std::isfinite(in.t_s) && std::isfinite(now_s);
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
  if (options_.hybrid_filter)
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
  // Publish the vibration filter for the current speed and rendered normal force.
  ArFilter& slot = filter_box_.WriteSlot();
  if (options_.vibration) {
    interp_.Interpolate(cmd.raw.tangential_speed_mps, cmd.raw.normal_force_N, cmd.raw.in_contact, &slot);
    if (neural_) slot.active = cmd.raw.in_contact;  // the neural synth applies its own minimum speed
  } else {
    slot.active = false;
  }
  slot.speed_mps = cmd.raw.tangential_speed_mps;
  slot.force_N = cmd.raw.normal_force_N;
  filter_box_.Publish();
  return cmd;
}

double HybridRenderer::VibrationTick() noexcept {
  counters_.vibration_ticks.fetch_add(1, std::memory_order_relaxed);
  const ArFilter& f = filter_box_.Read();
  // Run the AR model at the bank's rate; interpolate linearly to the loop's rate.
  phase_ += step_;
  while (phase_ >= 1.0) {
    phase_ -= 1.0;
    prev_ = next_;
    next_ = neural_ ? neural_->Step(f.speed_mps, f.force_N, f.active) : synth_.Step(f);
  }
  double a = prev_ + (next_ - prev_) * phase_;
  if (!f.active) {
    prev_ = next_ = 0;
    a = 0;
  }
  if (options_.hybrid_filter) a = vib_hp_.Step(a);
  return std::isfinite(a) ? a : 0.0;
}

}  // namespace hapticlab::renderer
