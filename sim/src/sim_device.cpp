#include "hapticlab/sim/sim_device.hpp"

#include <algorithm>
#include <cmath>

#include "hapticlab/sim_truth/friction.hpp"
#include "truth_internal.hpp"

namespace hapticlab::sim {
namespace {
constexpr double kBaseStiffness_N_per_m = 5000;  // a real sample's stiff base (the table)
constexpr double kContactReport_N = 0.3;         // "in contact" for contact_ticks()
}  // namespace

// ---------------------------------------------------------------------------------------------
TruthSample::TruthSample(const MaterialProfile& p, std::uint64_t seed, double vibration_rate_hz)
    : p_(p), geo_(std::make_shared<internal::TruthGeometry>(p)), rng_(seed) {
  offset_m_ = geo_->bound();  // keeps the texture's lowest point above the layer's floor
  top_m_ = p.layer_thickness_m + offset_m_;
  internal::Resonator(p.vibration_peak_hz, p.vibration_q, vibration_rate_hz, &c1_, &c2_, &var_);
}

TruthSample::Contact TruthSample::At(const Eigen::Vector3d& pos,
                                     const Eigen::Vector3d& vel) const noexcept {
  Contact c;
  const double x = pos.x(), y = pos.y(), z = pos.z(), vx = vel.x(), vy = vel.y(), vz = vel.z();
  c.speed_mps = std::hypot(vx, vy);
  const double ux = c.speed_mps > 0 ? vx / c.speed_mps : 0,
               uy = c.speed_mps > 0 ? vy / c.speed_mps : 0;
  double h, hx, hy;
  geo_->Full(x, y, ux, uy, &h, &hx, &hy, &c.micro_dd);
  const double top = p_.layer_thickness_m + offset_m_ + h;
  double d_t = 0, d_rate = 0;
  if (z < 0) {
    d_t = top;
    d_rate = hx * vx + hy * vy;
  } else if (z < top) {
    d_t = top - z;
    d_rate = hx * vx + hy * vy - vz;
  }
  const double dn = std::pow(std::max(d_t, 0.0), p_.hc_n);
  const double f_layer = std::max(0.0, p_.stiffness_N_per_m * dn + p_.damping * dn * d_rate);
  const double f_base = z < 0 ? kBaseStiffness_N_per_m * -z : 0.0;
  c.normal_N = f_layer + f_base;
  // Real surfaces push along their true normal; friction with Stribeck and load exponent.
  const Eigen::Vector3d normal = Eigen::Vector3d(-hx, -hy, 1.0).normalized();
  const double mu =
      sim_truth::StribeckFriction::FromRatio(p_.mu_k, p_.stribeck_ratio, p_.stribeck_speed_mps)
          .Mu(c.speed_mps);
  const double ff =
      c.normal_N > 0 ? mu * std::pow(c.normal_N, p_.load_exponent) * std::tanh(c.speed_mps / 1e-3)
                     : 0.0;
  c.force_N = c.normal_N * normal;
  c.force_N.x() -= ff * ux;
  c.force_N.y() -= ff * uy;
  c.penetration_m = d_t + std::max(0.0, -z);
  return c;
}

double TruthSample::Vibration(const Contact& c) noexcept {
  const bool contact = c.normal_N > 1e-3;
  const double rms = contact ? internal::VibrationRms(p_, c.speed_mps, c.normal_N) : 0.0;
  const double a = c1_ * a1_ + c2_ * a2_ + rms / std::sqrt(var_) * rng_.Normal();
  a2_ = a1_;
  a1_ = a;
  return a + (contact ? c.micro_dd * c.speed_mps * c.speed_mps : 0.0);
}

// ---------------------------------------------------------------------------------------------
Hand::Hand() : Hand(Options{}) {}
Hand::Hand(const Options& o) : o_(o) {}

void Hand::Begin(const Stroke& s, const Eigen::Isometry3d& device_from_sample, double top_m,
                 double stiffness, TruthSample* truth, double fr, double vr) {
  s_ = s;
  device_from_sample_ = device_from_sample;
  top_m_ = top_m;
  truth_ = truth;
  gain_ = 20.0 / std::max(stiffness, 50.0);  // ~20 rad/s force loop closed by the hand
  ux_ = std::cos(s.direction_rad);
  uy_ = std::sin(s.direction_rad);
  z_m_ = top_m;
  vz_mps_ = 0;
  t_s_ = 0;
  fn_felt_N_ = 0;
  z_contact_m_ = 0;
  touched_ = pending_ = interval_open_ = holding_ = false;
  fr_ = fr;
  vr_ = vr;
  vib_per_tick_ = std::max(1, static_cast<int>(std::lround(vr / fr)));
  acc_ = FeatureAccumulator(fr, vr);
  for (auto& b : shake_hp_)
    b = renderer::Biquad(renderer::BiquadCoeffs::ButterworthHighPass(40.0, fr));
  shake_last_ = 0;
  contact_ = {};
  contact_ticks_ = ticks_ = 0;
  double drop;
  while (actuator_.TryPop(&drop)) {
  }
}

void Hand::FlushInterval() noexcept {
  if (!interval_open_) return;
  interval_open_ = false;
  // The actuator's samples of the period (none when the method plays no vibration), the
  // shaking of the force felt, and the truth's contact vibration on a real side.
  int n = 0;
  double a;
  while (actuator_.TryPop(&a)) {
    acc_.AddVibration(a + shake_last_ + (truth_ ? truth_->Vibration(contact_) : 0.0));
    ++n;
  }
  for (; n < vib_per_tick_; ++n)
    acc_.AddVibration(shake_last_ + (truth_ ? truth_->Vibration(contact_) : 0.0));
}

void Hand::Hold(const Eigen::Isometry3d& device_from_sample, const Eigen::Vector3d& p_sample_m) {
  device_from_sample_ = device_from_sample;
  p_ = p_sample_m;
  v_.setZero();
  truth_ = nullptr;
  holding_ = true;
  pending_ = interval_open_ = false;
}

ToolState Hand::Step(double t_s) noexcept {
  if (holding_) {  // still: no stroke, no features (Push sees no pending step)
    t_s_ = t_s;
    ++ticks_;
    ToolState out;
    out.p_m = device_from_sample_ * p_;
    out.v_mps.setZero();
    return out;
  }
  FlushInterval();
  const double dt = t_s > t_s_ ? t_s - t_s_ : 1.0 / fr_;
  t_s_ = t_s;
  // Integral control of the felt normal force by the stylus height.
  const double z0 = z_m_;
  z_m_ = std::max(z_m_ - gain_ * (s_.force_N - fn_felt_N_) * dt, top_m_ - o_.max_descent_m);
  vz_mps_ = (z_m_ - z0) / dt;
  // Position along the stroke: a triangle wave of constant speed.
  const double period = 2 * s_.length_m / s_.speed_mps;
  const double ph = std::fmod(t_s, period) / period;
  const double d = ph < 0.5 ? 2 * ph * s_.length_m : (2 - 2 * ph) * s_.length_m;
  const double v = ph < 0.5 ? s_.speed_mps : -s_.speed_mps;
  p_ = {s_.x0_m + d * ux_, s_.y0_m + d * uy_, z_m_};
  v_ = {v * ux_, v * uy_, vz_mps_};
  if (truth_) contact_ = truth_->At(p_, v_);
  pending_ = true;
  ++ticks_;
  ToolState out;
  out.p_m = device_from_sample_ * p_;
  out.v_mps = device_from_sample_.linear() * v_;
  return out;
}

void Hand::Push(const Eigen::Vector3d& force_device_N) noexcept {
  const Eigen::Vector3d f_dev = device_from_sample_.linear().transpose() * force_device_N;
  Eigen::Vector3d f = f_dev;
  fn_felt_N_ = std::max(f_dev.z(), 0.0);
  if (truth_) {
    f += contact_.force_N;
    fn_felt_N_ += contact_.normal_N;
  }
  if (!pending_) return;  // a force after the run (the engine's closing zero): nothing to feel
  pending_ = false;
  if (!touched_ && fn_felt_N_ > o_.contact_N) {
    touched_ = true;
    z_contact_m_ = z_m_;
  }
  const double pen = touched_ ? std::max(z_contact_m_ - z_m_, 0.0) : 0.0;
  acc_.AddForce(f.z(), std::hypot(f.x(), f.y()), std::hypot(v_.x(), v_.y()), pen);
  if (fn_felt_N_ > kContactReport_N) ++contact_ticks_;
  const double speed = std::hypot(v_.x(), v_.y());
  const double ux = speed > 0 ? v_.x() / speed : 0, uy = speed > 0 ? v_.y() / speed : 0;
  const double ax = shake_hp_[0].Step(f.x()), ay = shake_hp_[1].Step(f.y()),
               az = shake_hp_[2].Step(f.z());
  shake_last_ = (ax * ux + ay * uy + az) / o_.mass_kg;
  interval_open_ = true;
}

void Hand::FeelVibration(double acc_mps2) noexcept { actuator_.TryPush(acc_mps2); }

Features Hand::Finish() noexcept {
  FlushInterval();
  return acc_.Result();
}

// ---------------------------------------------------------------------------------------------
SimDevice::SimDevice(const SimDeviceModel& m, Hand& hand, const devices::Clock* clock)
    : m_(m), hand_(hand), clock_(clock), rng_(m.seed) {}

devices::DeviceCapabilities SimDevice::Capabilities() const {
  devices::DeviceCapabilities c;
  c.name = m_.name;
  c.max_force_N = m_.max_force_N;
  c.max_stiffness_N_per_m = m_.max_stiffness_N_per_m;
  c.max_rate_hz = m_.max_rate_hz;
  return c;
}

void SimDevice::SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept { t0_ = t0; }

double SimDevice::Time() const noexcept {
  return clock_ ? clock_->Now()
                : std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
}

void SimDevice::Reset() noexcept {
  velocity_.Reset();
  dropout_start_s_ = -1;
  dropout_s_ = 0;
  empty_reads_ = lost_reads_ = 0;
  reads_.store(0, std::memory_order_relaxed);
}

devices::ReadResult SimDevice::Read(DeviceSample* out) noexcept {
  const double t = Time();
  // The hand moves whatever the link does.
  const ToolState s = hand_.Step(t);
  reads_.fetch_add(1, std::memory_order_relaxed);
  if (dropout_start_s_ >= 0 && t >= dropout_start_s_ && t < dropout_start_s_ + dropout_s_) {
    ++lost_reads_;
    return devices::ReadResult::kLost;
  }
  if (m_.empty_read_probability > 0 && rng_.Uniform() < m_.empty_read_probability) {
    ++empty_reads_;
    return devices::ReadResult::kNoNewData;
  }
  const double q = m_.encoder_resolution_m;
  const Eigen::Vector3d p = q > 0 ? Eigen::Vector3d((s.p_m / q).array().round() * q) : s.p_m;
  out->state.p_m = p;
  out->state.v_mps = velocity_.Update(p, t, m_.velocity_cutoff_hz);
  out->t_s = t;
  return devices::ReadResult::kOk;
}

void SimDevice::WriteForce(const Eigen::Vector3d& force_N) noexcept {
  Eigen::Vector3d f = force_N.allFinite() ? force_N : Eigen::Vector3d::Zero();
  const double n = f.norm();
  if (n > m_.max_force_N) f *= m_.max_force_N / n;  // the motors saturate
  hand_.Push(f);
}

// ---------------------------------------------------------------------------------------------
SimRig::SimRig(const SimDeviceModel& m, const std::array<Eigen::Isometry3d, 2>& poses,
               double vibration_rate_hz)
    : actuator(hand, vibration_rate_hz),
      generic(std::make_unique<SimDevice>(m, hand, &clock)),
      device(generic.get()),
      true_device_from_sample(poses) {}

std::array<Eigen::Isometry3d, 2> DefaultSamplePoses() {
  std::array<Eigen::Isometry3d, 2> p{Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()};
  p[0].translation() = Eigen::Vector3d(-0.03, 0, 0);
  p[1].translation() = Eigen::Vector3d(0.03, 0, 0);
  return p;
}

}  // namespace hapticlab::sim
