#pragma once
// Test doubles of the device interfaces (devices/device.hpp): a haptic device that replays a
// recorded trajectory against a clock, and an actuator that keeps what it is sent. Header-only;
// only tests use them.

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/core/status.hpp"
#include "hapticlab/devices/device.hpp"

namespace hapticlab::test {

/// One recorded tool sample.
struct TrajectorySample {
  double t_s = 0;
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_mps = Eigen::Vector3d::Zero();
};

/// Replays samples in time order against a clock (seconds since the replay started). Read
/// returns the latest sample at or before now, stamped with now; after the last sample the
/// link is lost. Commanded forces are kept (preallocated) for inspection.
class ReplayDevice : public devices::HapticDevice {
 public:
  /// @param samples at least one, in time order (PreconditionError otherwise)
  /// @param clock returns the current time [s] on the replay's time base
  ReplayDevice(std::vector<TrajectorySample> samples, std::function<double()> clock,
               devices::DeviceCapabilities caps = {})
      : samples_(std::move(samples)), clock_(std::move(clock)), caps_(std::move(caps)) {
    HL_REQUIRE(!samples_.empty(), "replay needs at least one sample");
    for (std::size_t i = 1; i < samples_.size(); ++i)
      HL_REQUIRE(samples_[i].t_s >= samples_[i - 1].t_s, "replay samples must be in time order");
    caps_.name = caps_.name.empty() ? "replay" : caps_.name;
    // Room for a 4 kHz loop over the whole trajectory, plus margin.
    const double span = samples_.back().t_s - samples_.front().t_s;
    forces_.reserve(static_cast<std::size_t>(span * 4000 * 1.5) + 1024);
  }
  devices::DeviceCapabilities Capabilities() const override { return caps_; }
  devices::ReadResult Read(DeviceSample* out) noexcept override {
    const double now = clock_() + samples_.front().t_s;
    if (now > samples_.back().t_s) {
      finished_.store(true);
      return devices::ReadResult::kLost;
    }
    while (next_ + 1 < samples_.size() && samples_[next_ + 1].t_s <= now) ++next_;
    out->state.p_m = samples_[next_].p_m;
    out->state.v_mps = samples_[next_].v_mps;
    out->t_s = now - samples_.front().t_s;
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& force_N) noexcept override {
    if (forces_.size() < forces_.capacity()) forces_.push_back(force_N);
  }
  /// Forces written so far (read after the loop stopped).
  const std::vector<Eigen::Vector3d>& forces() const { return forces_; }
  bool finished() const { return finished_.load(); }

 private:
  std::vector<TrajectorySample> samples_;
  std::function<double()> clock_;
  devices::DeviceCapabilities caps_;
  std::size_t next_ = 0;
  std::vector<Eigen::Vector3d> forces_;
  std::atomic<bool> finished_{false};
};

/// Keeps every sample (capacity reserved up front; extra samples are counted, not stored).
class BufferActuator : public devices::Actuator {
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

}  // namespace hapticlab::test
