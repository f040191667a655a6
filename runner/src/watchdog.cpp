#include "hapticlab/runner/watchdog.hpp"

#include <cmath>

namespace hapticlab::runner {

const char* FaultName(FaultKind k) {
  switch (k) {
    case FaultKind::kNone:
      return "none";
    case FaultKind::kDisconnect:
      return "disconnect";
    case FaultKind::kNaN:
      return "nan";
    case FaultKind::kStale:
      return "stale";
    case FaultKind::kDeadlineMiss:
      return "deadline-miss";
    case FaultKind::kBadCommand:
      return "bad-command";
    case FaultKind::kVibrationModel:
      return "vibration-model";
  }
  return "?";
}

Watchdog::Watchdog(const WatchdogOptions& o) : o_(o), events_(o.event_capacity) {}

void Watchdog::Reset() noexcept {
  tripped_.store(false, std::memory_order_release);
  last_ = FaultKind::kNone;
  misses_ = 0;
  run_ = 0;
  lost_run_ = 0;
  last_ok_s_ = 0;
}

Eigen::Vector3d Watchdog::Check(devices::ReadResult read, const DeviceSample& s, double now_s,
                                double late_s, double period_s, const Eigen::Vector3d& force,
                                bool vibration_fault) noexcept {
  ++tick_;
  misses_ = late_s > period_s ? misses_ + 1 : 0;
  FaultKind k = FaultKind::kNone;
  if (read == devices::ReadResult::kOk) {
    lost_run_ = 0;
    last_ok_s_ = now_s;
  }
  if (read == devices::ReadResult::kLost) {
    ++lost_run_;
    lost_reads_.fetch_add(1, std::memory_order_relaxed);
    if (lost_run_ < o_.max_lost_reads && now_s - last_ok_s_ < o_.max_lost_s) {
      // A short loss: no sample this tick, so no force; not (yet) a fault.
      run_ = 0;
      last_ = FaultKind::kNone;
      return Eigen::Vector3d::Zero();
    }
    k = FaultKind::kDisconnect;
  } else if (!s.state.p_m.allFinite() || !s.state.v_mps.allFinite() || !std::isfinite(s.t_s))
    k = FaultKind::kNaN;
  else if (now_s - s.t_s > o_.stale_after_s)
    k = FaultKind::kStale;
  else if (misses_ >= o_.max_consecutive_misses)
    k = FaultKind::kDeadlineMiss;
  else if (!force.allFinite() || force.norm() > o_.max_force_N * (1 + 1e-9))
    k = FaultKind::kBadCommand;
  else if (vibration_fault)
    k = FaultKind::kVibrationModel;
  run_ = k != FaultKind::kNone && k == last_ ? run_ + 1 : 0;
  last_ = k;
  if (k == FaultKind::kNone) return force;
  counts_[static_cast<std::size_t>(k)].fetch_add(1, std::memory_order_relaxed);
  tripped_.store(true, std::memory_order_release);
  if (run_ % 1000 == 0 && !events_.TryPush({k, now_s, tick_}))
    dropped_.fetch_add(1, std::memory_order_relaxed);
  return Eigen::Vector3d::Zero();
}

}  // namespace hapticlab::runner
