#include "hapticlab/sim/psychophysical_observer.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/psychophysics/psychometric.hpp"

namespace hapticlab::sim::psychophysical_observer_test {
namespace {

using psychophysics::Shape;
using psychophysics::SimulatedObserverParams;
using psychophysics::Task;

TEST(SimulatedObserver, AnswersWithItsPsychometricFunction) {
  // 3AFC at the threshold of a Weibull: P(correct) = 1/3 + (2/3 - 0.02)(1 - 1/e); wrong
  // answers spread evenly over the two other intervals.
  const SimulatedObserverParams o{
      .shape = Shape::kWeibull, .threshold = 0.2, .slope = 3, .lapse = 0.02};
  Rng rng(5);
  constexpr int kN = 200000;
  int correct = 0, counts[3] = {0, 0, 0};
  for (int i = 0; i < kN; ++i) {
    const auto a = SimulatedAnswer(o, Task::k3Afc, 0.2, 1, rng);
    correct += a.positive;
    ++counts[a.response];
    ASSERT_EQ(a.positive, a.response == 1);
  }
  const double p = 1.0 / 3 + (2.0 / 3 - 0.02) * (1 - std::exp(-1.0));
  // 5 binomial standard deviations: fails by chance with probability < 1e-6.
  EXPECT_NEAR(static_cast<double>(correct) / kN, p, 5 * std::sqrt(p * (1 - p) / kN));
  EXPECT_NEAR(counts[0], counts[2], 5 * std::sqrt(kN * (1 - p) / 2));
}

}  // namespace
}  // namespace hapticlab::sim::psychophysical_observer_test
