#pragma once
/// @file Velocity from successive position readings, as a device driver reports it: the finite
/// difference of the positions through a first-order low-pass. Used by every device that reads
/// only positions (the Falcon, the simulated devices), so the real device and its simulator
/// differentiate the same way.
///
/// Frame and units: whatever frame the positions are in (a device's frame, metres); velocity in
/// the same frame [m/s]. Real-time safe: no allocation, no locks, noexcept.

#include <Eigen/Core>
#include <cmath>
#include <numbers>

namespace hapticlab::devices {

class VelocityFilter {
 public:
  /// Takes the position `p_m` [m] read at `t_s` [s] and returns the velocity [m/s]: v moves
  /// towards (p - p_last) / dt by a = 1 - exp(-2 pi cutoff_hz dt), the exact step response of a
  /// first-order low-pass with cut-off `cutoff_hz` [Hz] for any (irregular) dt. The first
  /// reading after construction or Reset(), and a reading not later than the last, leave the
  /// velocity as it was.
  const Eigen::Vector3d& Update(const Eigen::Vector3d& p_m, double t_s, double cutoff_hz) noexcept {
    if (have_p_ && t_s > t_s_) {
      const double dt = t_s - t_s_, a = 1 - std::exp(-2 * std::numbers::pi * cutoff_hz * dt);
      v_mps_ += a * ((p_m - p_m_) / dt - v_mps_);
    }
    p_m_ = p_m;
    t_s_ = t_s;
    have_p_ = true;
    return v_mps_;
  }
  /// Forgets the last reading; the velocity is zero again.
  void Reset() noexcept {
    have_p_ = false;
    v_mps_.setZero();
    t_s_ = 0;
  }
  const Eigen::Vector3d& v_mps() const noexcept { return v_mps_; }

 private:
  Eigen::Vector3d p_m_ = Eigen::Vector3d::Zero(), v_mps_ = Eigen::Vector3d::Zero();
  double t_s_ = 0;
  bool have_p_ = false;
};

}  // namespace hapticlab::devices
