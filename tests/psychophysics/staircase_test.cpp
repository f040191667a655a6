#include "hapticlab/psychophysics/staircase.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/sim/psychophysical_observer.hpp"

namespace hapticlab::psychophysics::staircase_test {
namespace {

TEST(Staircase, OneUpTwoDownMovesByTheRules) {
  StaircaseConfig c;
  c.up = 1;
  c.down = 2;
  c.step_sizes = {0.1, 0.05};
  c.start_levels = {1.0};
  c.max_reversals = 100;
  c.max_trials = 100;
  // + + (down to 0.9) + + (down to 0.8) - (up: reversal at 0.8, step 0.05 -> 0.85)
  // + - (up: no reversal, 0.9) + + (down: reversal at 0.9 -> 0.85)
  std::vector<StaircaseTrial> h;
  const bool answers[] = {true, true, true, true, false, true, false, true, true};
  const double expected_levels[] = {1.0, 1.0, 0.9, 0.9, 0.8, 0.85, 0.85, 0.9, 0.9};
  for (int i = 0; i < 9; ++i) {
    const auto n = NextTrial(c, h, 1);
    ASSERT_FALSE(n.done);
    EXPECT_NEAR(n.level, expected_levels[i], 1e-12) << "trial " << i;
    h.push_back({n.track, n.level, answers[i]});
  }
  const auto t = ReplayStaircase(c, h)[0];
  ASSERT_EQ(t.reversal_levels.size(), 2u);
  EXPECT_NEAR(t.reversal_levels[0], 0.8, 1e-12);
  EXPECT_NEAR(t.reversal_levels[1], 0.9, 1e-12);
  EXPECT_NEAR(t.level, 0.85, 1e-12);
}

TEST(Staircase, LogStepsClampAndStop) {
  StaircaseConfig c;
  c.up = 1;
  c.down = 1;
  c.step_type = StepType::kLog;
  c.step_sizes = {std::log10(2.0)};
  c.start_levels = {1.0};
  c.min_level = 0.3;
  c.max_level = 10;
  c.max_reversals = 2;
  c.max_trials = 50;
  std::vector<StaircaseTrial> h;
  for (bool a : {true, true}) h.push_back({0, NextTrial(c, h, 0).level, a});
  EXPECT_NEAR(NextTrial(c, h, 0).level, 0.3, 1e-12);  // 1 -> 0.5 -> 0.25 clamped to 0.3
  h.push_back({0, 0.3, false});                       // reversal 1 at 0.3 -> 0.6
  h.push_back({0, NextTrial(c, h, 0).level, true});   // reversal 2 at 0.6: stop
  EXPECT_TRUE(NextTrial(c, h, 0).done);
  EXPECT_NEAR(TrackEstimate(c, ReplayStaircase(c, h)[0]), std::sqrt(0.3 * 0.6), 1e-12);
}

TEST(Staircase, ReplayRejectsARecordThatDoesNotFollowTheRules) {
  StaircaseConfig c;
  std::vector<StaircaseTrial> h{
      {0, 1.0, true}, {0, 1.0, true}, {0, 1.0, true}};  // third should be 0.9
  try {
    ReplayStaircase(c, h);
    ADD_FAILURE() << "replayed a record that breaks the rules";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].line, 3) << "the third trial";
    EXPECT_EQ(e.diagnostics()[0].field, "level");
  }
  h = {{3, 1.0, true}};
  EXPECT_THROW(ReplayStaircase(c, h), InputError);
  c.step_sizes = {};
  EXPECT_THROW(ReplayStaircase(c, {}), PreconditionError);
}

TEST(Staircase, InterleavedTracksAreChosenReproduciblyAndRunIndependently) {
  StaircaseConfig c;
  c.start_levels = {0.5, 0.05};
  c.step_sizes = {0.02};
  c.min_level = 0;
  c.max_trials = 30;
  c.max_reversals = 100;
  const SimulatedObserverParams o{.shape = Shape::kWeibull, .threshold = 0.2, .slope = 3};
  auto run = [&](std::uint64_t seed) {
    std::vector<StaircaseTrial> h;
    Rng rng(seed);
    for (;;) {
      const auto n = NextTrial(c, h, seed);
      if (n.done) break;
      h.push_back(
          {n.track, n.level, sim::SimulatedAnswer(o, Task::k2Afc, n.level, 0, rng).positive});
    }
    return h;
  };
  const auto a = run(9), b = run(9);
  ASSERT_EQ(a.size(), 60u);  // both tracks run to max_trials
  int track1 = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].track, b[i].track);
    EXPECT_EQ(a[i].level, b[i].level);
    track1 += a[i].track;
  }
  EXPECT_EQ(track1, 30);
  // Interleaved, not one track after the other: both appear among the first 30 trials.
  int first_half = 0;
  for (std::size_t i = 0; i < 30; ++i) first_half += a[i].track;
  EXPECT_GT(first_half, 5);
  EXPECT_LT(first_half, 25);
  EXPECT_NE(
      run(10).front().level + run(11).front().level + run(12).front().level + run(13).front().level,
      4 * a.front().level);  // another seed, another order
}

TEST(Staircase, TargetProbabilitiesAreLevitts) {
  // Levitt 1971, Table I: 1-up-2-down 70.7 %, 1-up-3-down 79.4 %, 2-up-1-down 29.3 %.
  EXPECT_NEAR(TargetProbability(1, 2), 0.7071, 1e-4);
  EXPECT_NEAR(TargetProbability(1, 3), 0.7937, 1e-4);
  EXPECT_NEAR(TargetProbability(2, 1), 0.2929, 1e-4);
  EXPECT_NEAR(TargetProbability(1, 1), 0.5, 1e-12);
}

// A 1-up-2-down staircase on a simulated 2AFC observer with a known Weibull converges on the
// stimulus where P(correct) = 70.7 % (Levitt 1971), not on the 79.4 % point of 1-up-3-down.
TEST(Staircase, OneUpTwoDownConvergesOnThe707PercentPoint) {
  const SimulatedObserverParams o{
      .shape = Shape::kWeibull, .threshold = 0.2, .slope = 3, .lapse = 0};
  const PsychometricParams truth{.threshold = 0.2, .slope = 3, .guess = 0.5, .lapse = 0};
  const double x707 = *StimulusAt(Shape::kWeibull, truth, 0.70710678);
  const double x794 = *StimulusAt(Shape::kWeibull, truth, TargetProbability(1, 3));
  StaircaseConfig c;
  c.up = 1;
  c.down = 2;
  c.step_sizes = {0.04, 0.01};  // a coarse first step, then small against the spread
  c.start_levels = {0.4};
  c.min_level = 0.005;
  c.max_reversals = 30;
  c.max_trials = 1000;
  c.discard_reversals = 6;
  constexpr int kRuns = 60;
  double sum = 0, sum2 = 0;
  for (int r = 0; r < kRuns; ++r) {
    Rng rng(DeriveSeed(31, static_cast<std::uint64_t>(r)));
    std::vector<StaircaseTrial> h;
    for (;;) {
      const auto n = NextTrial(c, h, 0);
      if (n.done) break;
      h.push_back(
          {n.track, n.level, sim::SimulatedAnswer(o, Task::k2Afc, n.level, 0, rng).positive});
    }
    const double e = TrackEstimate(c, ReplayStaircase(c, h)[0]);
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / kRuns, sd = std::sqrt((sum2 - kRuns * mean * mean) / (kRuns - 1));
  // Tolerance: 3 standard errors of the mean of the runs plus half the final step (Levitt's
  // result holds in the limit of small steps; a finite step biases by less than that).
  const double tol = 3 * sd / std::sqrt(kRuns) + 0.5 * 0.01;
  EXPECT_NEAR(mean, x707, tol) << "x70.7 = " << x707;
  EXPECT_GT(std::abs(mean - x794), tol) << "indistinguishable from the 79.4 % point " << x794;
}

}  // namespace
}  // namespace hapticlab::psychophysics::staircase_test
