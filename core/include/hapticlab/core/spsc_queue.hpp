#pragma once
/// @file Fixed-capacity single-producer / single-consumer ring buffer.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>

#include "hapticlab/core/status.hpp"

namespace hapticlab {

/// Wait-free ring buffer for exactly one producer thread and one consumer thread.
///
/// The buffer is allocated once in the constructor; TryPush and TryPop never allocate,
/// lock or wait, so a real-time thread may push. A full queue rejects the element and
/// counts it in overflow_count() (STYLE.md §5.4: overflow is counted, not blocked on).
/// @tparam T trivially copyable element type.
template <typename T>
class SpscQueue {
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds trivially copyable types");

 public:
  /// @param capacity number of elements the queue can hold; rounded up to a power of two.
  explicit SpscQueue(std::size_t capacity) {
    HL_REQUIRE(capacity >= 1 && capacity <= (std::size_t{1} << 30),
               "SpscQueue capacity must be in [1, 2^30]");
    std::size_t c = 1;
    while (c < capacity) c <<= 1;
    mask_ = c - 1;
    buffer_ = std::make_unique<T[]>(c);
  }

  std::size_t capacity() const { return mask_ + 1; }

  /// Producer side. Returns false (and counts an overflow) when the queue is full.
  bool TryPush(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ > mask_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ > mask_) {
        overflow_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
    }
    buffer_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer side. Returns false when the queue is empty.
  bool TryPop(T* out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    *out = buffer_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Approximate number of queued elements (exact when both sides are idle).
  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  /// Number of elements rejected because the queue was full.
  std::uint64_t overflow_count() const noexcept {
    return overflow_.load(std::memory_order_relaxed);
  }

 private:
  static constexpr std::size_t kLine = 64;  // cache line size on x86-64
  std::unique_ptr<T[]> buffer_;
  std::size_t mask_ = 0;
  alignas(kLine) std::atomic<std::size_t> head_{0};  // written by the producer
  std::size_t tail_cache_ = 0;                       // producer's view of tail_
  alignas(kLine) std::atomic<std::size_t> tail_{0};  // written by the consumer
  std::size_t head_cache_ = 0;                       // consumer's view of head_
  alignas(kLine) std::atomic<std::uint64_t> overflow_{0};
};

}  // namespace hapticlab
