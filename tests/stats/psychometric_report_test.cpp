#include "hapticlab/stats/psychometric_report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/stats/psychometric.hpp"

namespace hapticlab::stats::psychometric_report_test {
namespace {

TEST(PsychometricReport, BinsKeepEveryTrialInOrder) {
  PsychometricData d;
  Rng rng(4);
  for (int i = 0; i < 300; ++i) {
    d.x.push_back(std::round(rng.Uniform(0, 1) * 40) / 40);  // 41 distinct levels
    d.n.push_back(1);
    d.k.push_back(rng.Uniform() < d.x.back() ? 1 : 0);
  }
  const auto b = BinForPlot(d, 10);
  EXPECT_EQ(b.x.size(), 10u);
  int n = 0, k = 0, k0 = 0;
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    n += b.n[i];
    k += b.k[i];
    if (i > 0) {
      EXPECT_GT(b.x[i], b.x[i - 1]);
    }
  }
  for (int x : d.k) k0 += x;
  EXPECT_EQ(n, 300);
  EXPECT_EQ(k, k0);
  // Few levels: pooled exactly, not binned.
  const auto few = BinForPlot({{0.1, 0.2, 0.1}, {1, 1, 1}, {1, 0, 0}}, 10);
  EXPECT_EQ(few.x, (std::vector<double>{0.1, 0.2}));
  EXPECT_EQ(few.n, (std::vector<int>{2, 1}));
}

}  // namespace
}  // namespace hapticlab::stats::psychometric_report_test
