#include "hapticlab/runner/rt_thread.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>

namespace hapticlab::runner {
namespace {

// Touches `bytes` of stack below the caller's frame so the pages are mapped (and, after
// mlockall(MCL_FUTURE), locked) before the first tick. noinline: the array must be on this
// frame, not optimised away.
[[gnu::noinline]] void PrefaultStack(std::size_t bytes) {
  constexpr std::size_t kMax = std::size_t{256} * 1024;
  char buf[kMax];
  const std::size_t n = bytes < kMax ? bytes : kMax;
  for (std::size_t i = 0; i < n; i += 4096) buf[i] = 0;
  if (n) buf[n - 1] = 0;
  asm volatile("" : : "r"(buf) : "memory");  // the stores must happen
}

std::string Refused(int err) { return fmt::format("refused: {}", std::strerror(err)); }

}  // namespace

long CurrentTimerSlackNs() { return static_cast<long>(prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0)); }

MemoryLockReport LockMemory(bool requested) {
  MemoryLockReport r;
  if (!requested) return r;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    r.locked = true;
    r.status = "locked (mlockall MCL_CURRENT|MCL_FUTURE)";
  } else {
    const int e = errno;
    r.status =
        Refused(e) + (e == ENOMEM || e == EPERM
                          ? " (raise RLIMIT_MEMLOCK: memlock in limits.conf, or CAP_IPC_LOCK)"
                          : "");
  }
  return r;
}

RtThreadReport ConfigureRtThread(int priority, int cpu, std::size_t prefault_stack_bytes) {
  RtThreadReport r;
  // 1 ns: the smallest slack the kernel accepts (0 would mean "the default").
  if (prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0) != 0) r.priority_status = Refused(errno);
  r.timer_slack_ns = CurrentTimerSlackNs();
  if (priority <= 0) {
    r.priority_status = "not requested (normal scheduling)";
  } else {
    const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
    if (priority < lo || priority > hi) {
      r.priority_status = fmt::format(
          "refused: SCHED_FIFO priority {} outside {}..{} (normal scheduling)", priority, lo, hi);
    } else {
      sched_param sp{};
      sp.sched_priority = priority;
      const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
      if (rc == 0) {
        r.fifo = true;
        r.priority = priority;
        r.priority_status = fmt::format("SCHED_FIFO {}", priority);
      } else {
        r.priority_status = fmt::format(
            "refused: SCHED_FIFO {}: {}{} (normal scheduling)", priority, std::strerror(rc),
            rc == EPERM ? "; grant rtprio in limits.conf or CAP_SYS_NICE" : "");
      }
    }
  }
  if (cpu < 0) {
    r.affinity_status = "not requested";
  } else if (cpu >= CPU_SETSIZE) {
    r.affinity_status = fmt::format("refused: CPU {} out of range", cpu);
  } else {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (rc == 0) {
      r.cpu = cpu;
      r.affinity_status = fmt::format("CPU {}", cpu);
    } else {
      r.affinity_status = fmt::format("refused: CPU {}: {}", cpu, std::strerror(rc));
    }
  }
  if (prefault_stack_bytes > 0) {
    PrefaultStack(prefault_stack_bytes);
    r.stack_prefaulted = true;
  }
  return r;
}

}  // namespace hapticlab::runner
