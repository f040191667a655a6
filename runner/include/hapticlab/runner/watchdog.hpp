#pragma once
/// @file The force loop's watchdog: every tick it checks the device read (a sustained loss of
/// the link is a disconnect; a single lost read only zeroes that tick's force), the
/// sample (NaN, stale), the loop's lateness (consecutive missed deadlines) and the force about
/// to be commanded (NaN, above the device limit), and commands zero force on the very tick a
/// fault is seen. Faults latch for the trial (it is marked faulted and re-queued by the
/// runner) and go to a lock-free event queue that a non-real-time thread drains into the
/// study record's event log. Check() is noexcept and allocation-free.

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cstdint>

#include "hapticlab/core/spsc_queue.hpp"
#include "hapticlab/devices/device.hpp"
#include "hapticlab/renderer/hybrid.hpp"

namespace hapticlab::runner {

enum class FaultKind : std::uint8_t {
  kNone = 0,
  kDisconnect,
  kNaN,
  kStale,
  kDeadlineMiss,
  kBadCommand,
  kVibrationModel  ///< the renderer muted a runaway vibration model (ForceCommand::vibration_fault)
};
inline constexpr int kFaultKinds = 7;
/// "disconnect", "nan", "stale", "deadline-miss", "bad-command", "vibration-model"
const char* FaultName(FaultKind k);

struct WatchdogOptions {
  double stale_after_s = 0.005;    ///< device data older than this is stale
  int max_consecutive_misses = 3;  ///< late ticks in a row before it is a fault
  double max_force_N = 8.0;        ///< a command above this (before clamping) is a fault
  /// A loss is sustained (a disconnect fault) after this many lost reads in a row, or this
  /// long since the last good read, whichever comes first.
  int max_lost_reads = 10;
  double max_lost_s = 0.010;
  std::size_t event_capacity = 1024;
};

struct FaultEvent {
  FaultKind kind = FaultKind::kNone;
  double t_s = 0;
  std::uint64_t tick = 0;
};

class Watchdog {
 public:
  explicit Watchdog(const WatchdogOptions& o = {});
  /// One force tick: what the device read gave, the sample rendered (the newest good one;
  /// ignored on a lost read), the loop's time, how late the tick woke, and the force the
  /// renderer wants (and whether the renderer reported its vibration model muted this tick).
  /// Returns the force to command: `force`, or zero on a fault (the same tick) and on any lost
  /// read (a short loss zeroes the force without faulting the trial).
  Eigen::Vector3d Check(devices::ReadResult read, const DeviceSample& s, double now_s,
                        double late_s, double period_s, const Eigen::Vector3d& force,
                        bool vibration_fault = false) noexcept;
  /// The fault of the last Check (kNone when healthy).
  FaultKind last() const { return last_; }
  /// Any fault since Reset: the trial is faulted.
  bool tripped() const { return tripped_.load(std::memory_order_acquire); }
  std::uint64_t count(FaultKind k) const {
    return counts_[static_cast<std::size_t>(k)].load(std::memory_order_relaxed);
  }
  /// A new trial.
  void Reset() noexcept;
  /// Non-real-time side: the next fault event (each fault's first tick is queued, then one per
  /// 1000 ticks while it persists); false when none.
  bool PopEvent(FaultEvent* e) { return events_.TryPop(e); }
  std::uint64_t dropped_events() const { return dropped_.load(std::memory_order_relaxed); }
  /// Reads that were lost (each zeroed its tick's force).
  std::uint64_t lost_reads() const { return lost_reads_.load(std::memory_order_relaxed); }

 private:
  WatchdogOptions o_;
  SpscQueue<FaultEvent> events_;
  std::array<std::atomic<std::uint64_t>, kFaultKinds> counts_{};
  std::atomic<std::uint64_t> dropped_{0}, lost_reads_{0};
  std::atomic<bool> tripped_{false};
  FaultKind last_ = FaultKind::kNone;
  int misses_ = 0, lost_run_ = 0;
  double last_ok_s_ = 0;
  std::uint64_t tick_ = 0, run_ = 0;  // ticks, ticks the current fault has lasted
};

}  // namespace hapticlab::runner
