#pragma once
/// @file Allocation guard for real-time tests: counts the heap allocations the current thread
/// makes while a guard is alive, and forbids Eigen's heap while one is alive.
///
/// What it sees depends on the build (tests/util/alloc_guard.cpp):
/// - release/debug builds with HL_CHECK_RT_ALLOC=ON (the default): the test binaries define
///   malloc, calloc, realloc, reallocarray, free, aligned_alloc, posix_memalign, memalign,
///   valloc and pvalloc themselves, forwarding to glibc's __libc_* entry points, so every
///   C, C++ (libstdc++'s operator new calls malloc), Eigen and third-party-library allocation
///   on the guarded thread is counted;
/// - AddressSanitizer and ThreadSanitizer builds, or HL_CHECK_RT_ALLOC=OFF (valgrind,
///   heaptrack): the sanitizer runtime owns malloc, so only the global operator new family
///   is counted. There, Eigen's heap is caught instead by EIGEN_RUNTIME_NO_MALLOC (defined
///   project-wide by HL_CHECK_RT_ALLOC): a guarded Eigen allocation fails Eigen's assertion
///   and aborts the test in the -O0 ASan build, which keeps assertions (not under NDEBUG).

#include <cstdint>

namespace hapticlab::test {

/// True where the guard counts malloc-family calls (not only operator new).
#if defined(HL_GUARD_MALLOC) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
inline constexpr bool kGuardSeesMalloc = true;
#else
inline constexpr bool kGuardSeesMalloc = false;
#endif

/// Counts heap allocations made by the current thread while alive (like Drake's
/// LimitMalloc). Real-time code runs inside one and the test asserts count() == 0.
/// Guards nest. With EigenHeap::kForbid (the default) it also calls
/// Eigen::internal::set_is_malloc_allowed(false) and restores the previous value when it
/// ends; that flag is one process-wide bool, so guards on threads that run at the same time
/// pass EigenHeap::kLeave and the test forbids Eigen's heap once, on the thread that starts
/// them.
class NoAllocGuard {
 public:
  enum class EigenHeap { kForbid, kLeave };
  explicit NoAllocGuard(EigenHeap eigen = EigenHeap::kForbid);
  ~NoAllocGuard();
  NoAllocGuard(const NoAllocGuard&) = delete;
  NoAllocGuard& operator=(const NoAllocGuard&) = delete;
  std::uint64_t count() const;

 private:
  std::uint64_t start_;
  bool restore_eigen_;
  bool eigen_was_allowed_ = true;
};

/// Forbids Eigen's heap (process-wide) while alive, restoring the previous setting after.
class EigenNoMalloc {
 public:
  EigenNoMalloc();
  ~EigenNoMalloc();
  EigenNoMalloc(const EigenNoMalloc&) = delete;
  EigenNoMalloc& operator=(const EigenNoMalloc&) = delete;

 private:
  bool was_allowed_;
};

}  // namespace hapticlab::test
