#include "hapticlab/psychophysics/psychometric.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/psychophysics/simulated_observer.hpp"

namespace hapticlab::psychophysics::psychometric_test {
namespace {

TEST(Psychometric, ThresholdIsWhereTheCoreHasItsDefiningValue) {
  // Closed forms: F(alpha) = 1/2 (logistic, normal), 1 - 1/e (Weibull).
  EXPECT_DOUBLE_EQ(Core(Shape::kLogistic, 0.3, 0.3, 7), 0.5);
  EXPECT_DOUBLE_EQ(Core(Shape::kNormal, 0.3, 0.3, 7), 0.5);
  EXPECT_NEAR(Core(Shape::kWeibull, 0.3, 0.3, 7), 1 - std::exp(-1.0), 1e-15);
  // Phi(1) = 0.841344746068543 (tables); logistic at one slope unit: 1 / (1 + e^-1).
  EXPECT_NEAR(Core(Shape::kNormal, 1.5, 1.0, 2), 0.841344746068543, 1e-14);
  EXPECT_NEAR(Core(Shape::kLogistic, 1.5, 1.0, 2), 1 / (1 + std::exp(-1.0)), 1e-15);
  EXPECT_EQ(Core(Shape::kWeibull, 0.0, 1.0, 2), 0.0);
}

TEST(Psychometric, StimulusAtInvertsPsi) {
  for (Shape s : {Shape::kLogistic, Shape::kWeibull, Shape::kNormal}) {
    const PsychometricParams p{.threshold = 0.25, .slope = 3.5, .guess = 1.0 / 3, .lapse = 0.03};
    for (double target : {0.4, 0.5, 0.707, 0.9}) {
      const auto x = StimulusAt(s, p, target);
      ASSERT_TRUE(x) << ToString(s);
      EXPECT_NEAR(Psi(s, *x, p), target, 1e-12) << ToString(s) << " " << target;
    }
    EXPECT_FALSE(StimulusAt(s, p, 0.3));   // below the guess rate
    EXPECT_FALSE(StimulusAt(s, p, 0.98));  // above 1 - lapse
  }
}

TEST(Psychometric, ParsesNames) {
  EXPECT_EQ(ParseShape("weibull"), Shape::kWeibull);
  EXPECT_FALSE(ParseShape("Weibull"));
  EXPECT_EQ(ParseTask("3afc"), Task::k3Afc);
  EXPECT_EQ(GuessRate(Task::k2Afc), 0.5);
  EXPECT_EQ(GuessRate(Task::kYesNo, 0.1), 0.1);
}

}  // namespace
}  // namespace hapticlab::psychophysics::psychometric_test
