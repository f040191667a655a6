#pragma once
/// @file Devices for offline work and tests: a haptic device that replays a recorded
/// trajectory against a clock, and an actuator that keeps what it is sent.

#include <atomic>
#include <functional>
#include <vector>

#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {

/// One recorded tool sample.
struct TrajectorySample {
  double t_s = 0;
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_mps = Eigen::Vector3d::Zero();
};

/// Replays samples in time order against a clock (seconds since the replay started). Read
/// returns the latest sample at or before now, stamped with now; after the last sample the
/// link is lost. Commanded forces are kept (preallocated) for inspection.
class ReplayDevice : public HapticDevice {
 public:
  /// @param samples at least one, in time order (a precondition: a caller that reads them
  ///        from a file checks them and reports an InputError first; PreconditionError here)
  /// @param clock returns the current time [s] on the replay's time base
  ReplayDevice(std::vector<TrajectorySample> samples, std::function<double()> clock,
               DeviceCapabilities caps = {});
  DeviceCapabilities Capabilities() const override { return caps_; }
  ReadResult Read(DeviceSample* out) noexcept override;
  void WriteForce(const Eigen::Vector3d& force_N) noexcept override;
  /// Forces written so far (read after the loop stopped).
  const std::vector<Eigen::Vector3d>& forces() const { return forces_; }
  bool finished() const { return finished_.load(); }

 private:
  std::vector<TrajectorySample> samples_;
  std::function<double()> clock_;
  DeviceCapabilities caps_;
  std::size_t next_ = 0;
  std::vector<Eigen::Vector3d> forces_;
  std::atomic<bool> finished_{false};
};

/// Keeps every sample (capacity reserved up front; extra samples are counted, not stored).
class BufferActuator : public Actuator {
 public:
  BufferActuator(double rate_hz, std::size_t capacity) : rate_hz_(rate_hz) {
    samples_.reserve(capacity);
  }
  double SampleRateHz() const override { return rate_hz_; }
  void Write(double acc_mps2) noexcept override {
    if (samples_.size() < samples_.capacity())
      samples_.push_back(acc_mps2);
    else
      ++dropped_;
  }
  const std::vector<double>& samples() const { return samples_; }
  std::size_t dropped() const { return dropped_; }

 private:
  double rate_hz_;
  std::vector<double> samples_;
  std::size_t dropped_ = 0;
};

}  // namespace hapticlab::devices
