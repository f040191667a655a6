#pragma once
/// @file How a real-time loop thread sets itself up before its first tick, and what it got.
/// Every request is best effort: a refusal (no privilege, a bad value) is reported in
/// RtThreadReport, never thrown. docs/hardware.md says how a lab grants the privileges.
///
/// - Timer slack 1 ns (prctl(PR_SET_TIMERSLACK), always; needs no privilege): the kernel
///   otherwise lets an ordinary thread's timer fire up to 50 us late to batch wake-ups.
/// - A spin phase: the loop sleeps until `spin_us` before its deadline, then busy-waits on the
///   clock (costs spin_us of CPU per tick; the force loop only).
/// - SCHED_FIFO at `priority` (RLIMIT_RTPRIO or CAP_SYS_NICE), mlockall(MCL_CURRENT |
///   MCL_FUTURE) (RLIMIT_MEMLOCK or CAP_IPC_LOCK), pinning to one CPU, and touching the stack
///   so its pages are resident before the first tick.

#include <cstddef>
#include <string>

namespace hapticlab::runner {

/// The spin before each force deadline when none is asked for [us]: measured on the
/// development machine (docs/performance.md), it takes the median wake-up lateness from the
/// timer's ~5-60 us to under 1 us at a cost of 2 % of a core at 1 kHz.
inline constexpr double kDefaultSpinUs = 20;

struct RtThreadOptions {
  int priority = 0;  ///< SCHED_FIFO priority of the force loop (1..99; 0: normal scheduling)
  bool lock_memory = false;         ///< mlockall(MCL_CURRENT | MCL_FUTURE) before the loops start
  int cpu = -1;                     ///< pin the force loop to this CPU (-1: no pinning)
  double spin_us = kDefaultSpinUs;  ///< busy-wait this long before each force deadline (0: none)
  /// Stack touched before the first tick (0: none).
  std::size_t prefault_stack_bytes = std::size_t{64} * 1024;
};

/// What a thread (or the process, for memory locking) got; strings for people and records.
struct RtThreadReport {
  long timer_slack_ns = -1;     ///< read back with prctl(PR_GET_TIMERSLACK) on the thread
  bool fifo = false;            ///< SCHED_FIFO granted
  int priority = 0;             ///< the granted SCHED_FIFO priority (0: normal scheduling)
  std::string priority_status;  ///< "SCHED_FIFO 80", "not requested", "refused: ..."
  int cpu = -1;                 ///< the CPU pinned to (-1: none)
  std::string affinity_status;  ///< "not requested", "CPU 1", "refused: ..."
  bool stack_prefaulted = false;
};

/// Process-wide: mlockall when asked. Returns whether memory is locked and a status line.
struct MemoryLockReport {
  bool locked = false;
  std::string status = "not requested";
};
MemoryLockReport LockMemory(bool requested);

/// Runs on the loop thread itself, before its first tick (allocates: not real-time).
/// `priority` and `cpu` are what this thread should ask for (the engine gives the vibration
/// loop one priority below the force loop).
RtThreadReport ConfigureRtThread(int priority, int cpu, std::size_t prefault_stack_bytes);

/// Reads back this thread's timer slack [ns] (prctl(PR_GET_TIMERSLACK)).
long CurrentTimerSlackNs();

}  // namespace hapticlab::runner
