#include "hapticlab/core/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::triple_buffer_test {
namespace {

// A value whose fields must agree: a torn read (half old, half new) breaks the relation.
struct Snapshot {
  std::uint64_t seq = 0;
  std::uint64_t twice = 0;
  double third = 0;
  std::uint64_t check = 0;  // seq ^ constant
};
constexpr std::uint64_t kMask = 0x9e3779b97f4a7c15ull;
Snapshot Make(std::uint64_t seq) {
  return {seq, 2 * seq, static_cast<double>(seq) / 3.0, seq ^ kMask};
}
bool Consistent(const Snapshot& s) {
  return s.twice == 2 * s.seq && s.third == static_cast<double>(s.seq) / 3.0 &&
         s.check == (s.seq ^ kMask);
}

TEST(TripleBuffer, ReadsTheInitialValueUntilSomethingIsPublished) {
  TripleBuffer<Snapshot> b(Make(7));
  EXPECT_EQ(b.Read().seq, 7u);
  b.WriteSlot() = Make(8);  // written, not yet published
  EXPECT_EQ(b.Read().seq, 7u);
  b.Publish();
  EXPECT_EQ(b.Read().seq, 8u);
  EXPECT_EQ(b.Read().seq, 8u) << "reading again without a publish keeps the value";
}

TEST(TripleBuffer, TheReaderGetsTheNewestOfSeveralPublishes) {
  TripleBuffer<Snapshot> b;
  for (std::uint64_t s = 1; s <= 5; ++s) {
    b.WriteSlot() = Make(s);
    b.Publish();
  }
  EXPECT_EQ(b.Read().seq, 5u);
  b.WriteSlot() = Make(6);
  b.Publish();
  b.WriteSlot() = Make(7);
  b.Publish();
  EXPECT_EQ(b.Read().seq, 7u);
}

TEST(TripleBuffer, TheWriterNeverWritesTheSlotTheReaderHolds) {
  TripleBuffer<Snapshot> b;
  for (std::uint64_t s = 1; s <= 50; ++s) {
    // Interleavings of 0-2 publishes per read visit every slot assignment.
    for (std::uint64_t p = 0; p < s % 3; ++p) {
      ASSERT_NE(&b.WriteSlot(), &b.Read());
      b.WriteSlot() = Make(100 * s + p);
      b.Publish();
    }
    const Snapshot& held = b.Read();
    const Snapshot copy = held;
    b.WriteSlot() = Make(999);  // the writer fills its slot while the reader holds its value
    EXPECT_NE(&b.WriteSlot(), &held);
    EXPECT_EQ(held.seq, copy.seq);
    b.Publish();
  }
}

TEST(TripleBuffer, PublishAndReadAllocateNothing) {
  TripleBuffer<Snapshot> b;
  test::NoAllocGuard guard;
  std::uint64_t sum = 0;
  for (std::uint64_t s = 0; s < 1000; ++s) {
    b.WriteSlot() = Make(s);
    b.Publish();
    sum += b.Read().seq;
  }
  EXPECT_EQ(sum, 999u * 1000u / 2);
  EXPECT_EQ(guard.count(), 0u);
}

// Run under ThreadSanitizer in CI (scripts/test): the hand-off must be race free, and the
// reader must only ever see whole values, in publication order.
TEST(TripleBuffer, TwoThreadsSeeWholeValuesInOrder) {
  constexpr std::uint64_t kLast = test::kSanitizerBuild ? 20000 : 200000;
  TripleBuffer<Snapshot> b(Make(0));
  std::thread writer([&] {
    for (std::uint64_t s = 1; s <= kLast; ++s) {
      b.WriteSlot() = Make(s);
      b.Publish();
    }
  });
  std::uint64_t last = 0, reads = 0, torn = 0, backwards = 0, distinct = 0;
  while (last < kLast) {
    const Snapshot v = b.Read();
    ++reads;
    torn += !Consistent(v);
    backwards += v.seq < last;
    distinct += v.seq > last;
    if (v.seq > last) last = v.seq;
  }
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kLast);
  EXPECT_GE(distinct, 1u);
  EXPECT_GE(reads, distinct);
}

}  // namespace
}  // namespace hapticlab::triple_buffer_test
