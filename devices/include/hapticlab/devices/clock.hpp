#pragma once
/// @file The loops' clock seam. The real-time engine runs either on the real clock (threads
/// sleeping to absolute deadlines) or on a VirtualClock that it steps itself, tick by tick,
/// as fast as the tick code runs (simulated sessions, tests). Devices that model time (the
/// simulated devices) read the same clock, so a virtual run is deterministic.

#include <atomic>
#include <chrono>

namespace hapticlab::devices {

/// Seconds since the loops' time zero.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual double Now() const noexcept = 0;
};

/// Seconds since construction on the steady clock (a simulated device on the real clock).
class SteadyClock final : public Clock {
 public:
  double Now() const noexcept override {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

/// A clock that only moves when told to (the engine sets it before every tick in a virtual run).
class VirtualClock final : public Clock {
 public:
  double Now() const noexcept override { return t_s_.load(std::memory_order_acquire); }
  void Set(double t_s) noexcept { t_s_.store(t_s, std::memory_order_release); }

 private:
  std::atomic<double> t_s_{0};
};

}  // namespace hapticlab::devices
