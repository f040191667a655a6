#include "hapticlab/core/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::spsc_queue_test {
namespace {

TEST(SpscQueue, CapacityRoundsUpToPowerOfTwo) {
  SpscQueue<int> q(5);
  EXPECT_EQ(q.capacity(), 8u);
}

TEST(SpscQueue, FullQueueRejectsAndCountsOverflow) {
  SpscQueue<int> q(4);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.TryPush(i));
  EXPECT_FALSE(q.TryPush(99));
  EXPECT_FALSE(q.TryPush(100));
  EXPECT_EQ(q.overflow_count(), 2u);
  int v = -1;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.TryPop(&v));
    EXPECT_EQ(v, i);  // FIFO, the rejected values never appear
  }
  EXPECT_FALSE(q.TryPop(&v));
}

TEST(SpscQueue, PushAndPopDoNotAllocate) {
  SpscQueue<double> q(16);
  test::NoAllocGuard guard;
  for (int i = 0; i < 100; ++i) {
    q.TryPush(i);
    double x;
    q.TryPop(&x);
  }
  EXPECT_EQ(guard.count(), 0u);
}

TEST(SpscQueue, TwoThreadsTransferEveryElementInOrder) {
  // A small queue forces many wrap-arounds and full/empty transitions.
  SpscQueue<std::uint64_t> q(64);
  constexpr std::uint64_t kCount = 2'000'000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kCount;) {
      if (q.TryPush(i))
        ++i;
      else
        std::this_thread::yield();  // on a loaded machine the consumer may be descheduled
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t v;
  while (expected < kCount) {
    if (q.TryPop(&v)) {
      ASSERT_EQ(v, expected);
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_FALSE(q.TryPop(&v));
}

}  // namespace
}  // namespace hapticlab::spsc_queue_test
