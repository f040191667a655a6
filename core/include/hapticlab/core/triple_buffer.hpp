#pragma once
/// @file Latest-value hand-off between one writer thread and one reader thread.

#include <atomic>
#include <cstdint>
#include <type_traits>

namespace hapticlab {

/// Triple buffer: the writer publishes whole values, the reader always gets the newest
/// complete one. Neither side ever waits, locks or allocates.
template <typename T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "TripleBuffer holds trivially copyable types");

 public:
  explicit TripleBuffer(const T& initial = T{}) {
    for (auto& b : buf_) b = initial;
  }
  /// Writer: the slot to fill, then Publish().
  T& WriteSlot() noexcept { return buf_[write_]; }
  void Publish() noexcept {
    const std::uint32_t prev = middle_.exchange(write_ | kFresh, std::memory_order_acq_rel);
    write_ = prev & kIndex;
  }
  /// Reader: refreshes to the newest published value (if any) and returns it.
  const T& Read() noexcept {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      const std::uint32_t prev = middle_.exchange(read_, std::memory_order_acq_rel);
      read_ = prev & kIndex;
    }
    return buf_[read_];
  }

 private:
  static constexpr std::uint32_t kFresh = 4, kIndex = 3;
  T buf_[3];
  std::uint32_t write_ = 0;               // writer-owned index
  std::atomic<std::uint32_t> middle_{1};  // shared index | fresh flag
  std::uint32_t read_ = 2;                // reader-owned index
};

}  // namespace hapticlab
