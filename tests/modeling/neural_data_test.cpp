// The neural models' training data (modeling/src/neural_data.cpp): the grid helpers and the
// ideal band split the networks train on, against properties computed here from the
// definitions (Parseval, exact reconstruction), not from the code.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "../../modeling/src/neural_internal.hpp"

namespace hapticlab::modeling::neural_internal::neural_data_test {
namespace {

TEST(NeuralData, GridValuesAreMatchedWithinARelativeTolerance) {
  const auto g = Unique({0.08, 0.04, 0.12, 0.04 * (1 + 1e-9), 0.08});
  ASSERT_EQ(g.size(), 3u);
  EXPECT_EQ(g[0], 0.04);
  EXPECT_EQ(Index(g, 0.12 * (1 - 1e-8)), 2);  // a value read back from a text file
  EXPECT_EQ(Index(g, 0.1), -1);
  EXPECT_FALSE(Near(1.0, 1.0 + 1e-5));
}

TEST(NeuralData, BandSplitIsAnIdealBandPassWhoseBandsSumToTheSignal) {
  const double fs = 2000;
  const std::size_t n = 4000;  // 2 s: 0.5 Hz bins, so the tones below sit on bins
  std::vector<double> x(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x[k] = std::sin(2 * std::numbers::pi * 60 * t) +
           0.5 * std::sin(2 * std::numbers::pi * 300 * t) +
           0.25 * std::cos(2 * std::numbers::pi * 700 * t);
  }
  const auto b1 = BandSplit(x, fs, 0, 100), b2 = BandSplit(x, fs, 100, 500),
             b3 = BandSplit(x, fs, 500, 1000 + 1);
  double worst = 0, e60 = 0, e300 = 0;
  for (std::size_t k = 0; k < n; ++k) {
    worst = std::max(worst, std::abs(b1[k] + b2[k] + b3[k] - x[k]));
    const double t = static_cast<double>(k) / fs;
    e60 = std::max(e60, std::abs(b1[k] - std::sin(2 * std::numbers::pi * 60 * t)));
    e300 = std::max(e300, std::abs(b2[k] - 0.5 * std::sin(2 * std::numbers::pi * 300 * t)));
  }
  EXPECT_LT(worst, 1e-12);  // the bands partition the spectrum
  EXPECT_LT(e60, 1e-12);    // each band holds exactly its own tone
  EXPECT_LT(e300, 1e-12);
  EXPECT_EQ(BandSplit({1.0}, fs, 0, 100), std::vector<double>{1.0});  // too short to split
}

}  // namespace
}  // namespace hapticlab::modeling::neural_internal::neural_data_test
