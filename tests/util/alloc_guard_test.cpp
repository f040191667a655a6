// The allocation guard must see what it claims to see, or every "allocates nothing" test
// that uses it passes vacuously.
#include "hapticlab/test/alloc_guard.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cstdlib>
#include <thread>
#include <vector>

namespace hapticlab::test {
namespace {

// Called through volatile pointers so the compiler cannot pair and elide the calls.
void* (*volatile g_malloc)(std::size_t) = std::malloc;
void* (*volatile g_calloc)(std::size_t, std::size_t) = std::calloc;
void* (*volatile g_realloc)(void*, std::size_t) = std::realloc;
void* (*volatile g_aligned_alloc)(std::size_t, std::size_t) = std::aligned_alloc;
void (*volatile g_free)(void*) = std::free;
void* volatile g_sink = nullptr;

TEST(AllocGuard, CountsMallocFamilyCallsOnTheGuardedThread) {
  if (!kGuardSeesMalloc) GTEST_SKIP() << "sanitizer build: malloc belongs to the sanitizer";
  NoAllocGuard guard(NoAllocGuard::EigenHeap::kLeave);
  void* p = g_malloc(24);
  EXPECT_EQ(guard.count(), 1u) << "malloc";
  p = g_realloc(p, 4096);
  EXPECT_EQ(guard.count(), 2u) << "realloc";
  g_free(p);
  p = g_calloc(8, 8);
  EXPECT_EQ(guard.count(), 3u) << "calloc";
  g_free(p);
  p = g_aligned_alloc(64, 256);
  EXPECT_EQ(guard.count(), 4u) << "aligned_alloc";
  g_free(p);
  void* q = nullptr;
  ASSERT_EQ(posix_memalign(&q, 64, 128), 0);
  EXPECT_EQ(guard.count(), 5u) << "posix_memalign";
  g_free(q);
  g_free(nullptr);
  EXPECT_EQ(guard.count(), 5u) << "free is not an allocation";
}

TEST(AllocGuard, CountsOperatorNewAndContainerGrowth) {
  NoAllocGuard guard(NoAllocGuard::EigenHeap::kLeave);
  g_sink = new int(7);
  EXPECT_GE(guard.count(), 1u);
  delete static_cast<int*>(g_sink);
  const auto before = guard.count();
  std::vector<double> v;
  v.push_back(1.0);
  g_sink = v.data();
  EXPECT_GT(guard.count(), before);
}

TEST(AllocGuard, SeesEigenDynamicMatrices) {
  if (!kGuardSeesMalloc) GTEST_SKIP() << "sanitizer build: see ForbidsEigenHeapWhereAssertsAreOn";
  NoAllocGuard guard(NoAllocGuard::EigenHeap::kLeave);
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(64, 0.0, 1.0);
  g_sink = x.data();
  EXPECT_GE(guard.count(), 1u);
  EXPECT_DOUBLE_EQ(x.sum(), 32.0);
}

TEST(AllocGuard, FixedSizeEigenAndArithmeticAllocateNothing) {
  NoAllocGuard guard;
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity() * 2.0;
  Eigen::Vector3d b = a * Eigen::Vector3d(1, 2, 3);
  EXPECT_DOUBLE_EQ(b.sum(), 12.0);
  EXPECT_EQ(guard.count(), 0u);
}

#if defined(EIGEN_RUNTIME_NO_MALLOC) && !defined(NDEBUG)
TEST(AllocGuardDeathTest, ForbidsEigenHeapWhereAssertsAreOn) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        NoAllocGuard guard;
        Eigen::VectorXd x(64);
        g_sink = x.data();
      },
      "heap allocation is forbidden");
}
#endif

TEST(AllocGuard, NestsAndIgnoresOtherThreads) {
  std::atomic<int> step{0};
  std::thread other([&] {
    while (step.load() != 1) std::this_thread::yield();
    g_free(g_malloc(32));
    g_sink = new int(1);
    delete static_cast<int*>(g_sink);
    step = 2;
  });
  NoAllocGuard outer(NoAllocGuard::EigenHeap::kLeave);
  step = 1;
  while (step.load() != 2) std::this_thread::yield();
  EXPECT_EQ(outer.count(), 0u) << "another thread's allocations";
  {
    NoAllocGuard inner(NoAllocGuard::EigenHeap::kLeave);
    g_sink = new int(2);
    delete static_cast<int*>(g_sink);
    EXPECT_EQ(inner.count(), 1u);
  }
  EXPECT_EQ(outer.count(), 1u) << "the outer guard sees what the inner one saw";
  other.join();
}

}  // namespace
}  // namespace hapticlab::test
