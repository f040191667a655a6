// LatencySummary's percentiles against the nearest-rank percentile of the sorted values
// (the definition cyclictest and most papers use): never below it, at most one bin (0.5 us)
// above; merging and the sparse storage form keep every count.

#include "hapticlab/core/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace hapticlab::latency_histogram_test {
namespace {

double NearestRank(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::max<std::size_t>(k, 1) - 1];
}

TEST(LatencyHistogram, PercentilesBoundTheNearestRankPercentileWithinOneBin) {
  std::mt19937_64 g(3);
  std::lognormal_distribution<double> d(std::log(8e-6), 0.8);  // a wake-up-like skewed spread
  LatencyHistogram h;
  std::vector<double> v;
  for (int i = 0; i < 20000; ++i) {
    const double x = d(g);
    v.push_back(x);
    h.Add(x);
  }
  v.push_back(7e-3);  // one value beyond the last regular bin
  h.Add(7e-3);
  const auto s = h.Snapshot();
  EXPECT_EQ(s.total, v.size());
  EXPECT_EQ(s.max_s, 7e-3);
  for (const double q : {0.5, 0.9, 0.99, 0.999}) {
    const double ref = NearestRank(v, q);
    EXPECT_GE(s.Quantile(q), ref - 1e-15) << q;
    EXPECT_LE(s.Quantile(q), ref + LatencySummary::kBinWidthS) << q;
  }
  EXPECT_EQ(s.Quantile(1.0), 7e-3);
}

TEST(LatencyHistogram, NegativeValuesCountAsZeroAndEmptyIsZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.Snapshot().Quantile(0.5), 0.0);
  h.Add(-3e-6);
  EXPECT_EQ(h.Snapshot().counts[0], 1u);
}

TEST(LatencyHistogram, MergeAndSparseFormKeepEveryCount) {
  LatencyHistogram a, b;
  for (int i = 0; i < 100; ++i) a.Add(i * 1e-6);
  for (int i = 0; i < 50; ++i) b.Add(20e-6 + i * 3e-6);
  b.Add(1.0);
  LatencySummary m = a.Snapshot();
  m.Merge(b.Snapshot());
  EXPECT_EQ(m.total, 151u);
  EXPECT_EQ(m.max_s, 1.0);
  LatencySummary back;
  ASSERT_TRUE(back.ParseSparse(m.Sparse(), m.max_s));
  EXPECT_EQ(back.counts, m.counts);
  EXPECT_EQ(back.total, m.total);
  EXPECT_FALSE(back.ParseSparse("3:4 x", 0));
  EXPECT_FALSE(back.ParseSparse("99999:1", 0));
}

// `rig check`'s text histogram (rows of 1 us): a tick in the overflow bin (>= 5 ms) is counted
// once, in the overflow row, and nothing is read past the bins (the row loop used to read
// counts[kBins + 1], an "> 99 us" row of 80664 for 3004 ticks).
TEST(LatencyHistogram, RowsCountATickInTheOverflowBinOnce) {
  LatencyHistogram h;
  h.Add(7e-3);  // overflow bin only
  std::uint64_t beyond = 99;
  auto rows = h.Snapshot().Rows(2, 100, &beyond);
  EXPECT_TRUE(rows.empty());
  EXPECT_EQ(beyond, 1u);
  // Mixed: 3 ticks at 0.2 us (row 0), 2 at 1.7 us (row 1), one at 150 us (past the 100 rows),
  // one in the overflow bin. Counted by hand, not by the histogram.
  for (int i = 0; i < 3; ++i) h.Add(0.2e-6);
  for (int i = 0; i < 2; ++i) h.Add(1.7e-6);
  h.Add(150e-6);
  const auto s = h.Snapshot();
  rows = s.Rows(2, 100, &beyond);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], 3u);
  EXPECT_EQ(rows[1], 2u);
  EXPECT_EQ(beyond, 2u);
  EXPECT_EQ(rows[0] + rows[1] + beyond, s.total);
  // Every bin a row of its own, 10001 rows asked: the overflow bin still counts once.
  rows = s.Rows(1, LatencySummary::kBins + 1, &beyond);
  EXPECT_EQ(beyond, 1u);
  std::uint64_t sum = beyond;
  for (const auto n : rows) sum += n;
  EXPECT_EQ(sum, s.total);
}

}  // namespace
}  // namespace hapticlab::latency_histogram_test
