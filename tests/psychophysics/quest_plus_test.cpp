#include "hapticlab/psychophysics/quest_plus.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/sim/psychophysical_observer.hpp"

namespace hapticlab::psychophysics::quest_plus_test {
namespace {

std::vector<double> LogSpace(double lo, double hi, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(lo * std::pow(hi / lo, i / (n - 1.0)));
  return v;
}

QuestPlusConfig Config() {
  QuestPlusConfig c;
  c.shape = Shape::kWeibull;
  c.guess = 0.5;
  c.stimuli = LogSpace(0.02, 0.8, 30);
  c.thresholds = LogSpace(0.05, 0.5, 21);
  c.slopes = {1.5, 2, 3, 4.5, 6};
  c.lapses = {0, 0.02, 0.04};
  return c;
}

TEST(QuestPlus, UpdateIsBayesRuleOnTheGrid) {
  QuestPlus q(Config());
  const std::size_t j = 7;
  q.Update(j, true);
  q.Update(j + 3, false);
  double z = 0;
  std::vector<double> expect;
  for (std::size_t k = 0; k < q.posterior().size(); ++k) {
    const auto p = q.Point(k);
    const PsychometricParams th{p.threshold, p.slope, 0.5, p.lapse};
    const double l = Psi(Shape::kWeibull, q.config().stimuli[j], th) *
                     (1 - Psi(Shape::kWeibull, q.config().stimuli[j + 3], th));
    expect.push_back(l);
    z += l;
  }
  for (std::size_t k = 0; k < expect.size(); ++k)
    EXPECT_NEAR(q.posterior()[k], expect[k] / z, 1e-14);
}

TEST(QuestPlus, PlacesTheStimulusOfLeastExpectedEntropy) {
  // Watson 2017, steps 3-5, computed literally: for each stimulus, the posterior after each
  // outcome (through Update), its entropy, weighted by the outcome's predictive probability.
  QuestPlus q(Config());
  q.Update(10, true);
  q.Update(4, false);
  std::size_t best = 0;
  double best_h = INFINITY;
  for (std::size_t j = 0; j < q.config().stimuli.size(); ++j) {
    double p_pos = 0;
    for (std::size_t k = 0; k < q.posterior().size(); ++k) {
      const auto p = q.Point(k);
      p_pos += q.posterior()[k] *
               Psi(Shape::kWeibull, q.config().stimuli[j], {p.threshold, p.slope, 0.5, p.lapse});
    }
    QuestPlus yes = q, no = q;
    yes.Update(j, true);
    no.Update(j, false);
    const double h = p_pos * yes.Entropy() + (1 - p_pos) * no.Entropy();
    EXPECT_NEAR(q.ExpectedEntropy(j), h, 1e-10) << j;
    if (h < best_h) best_h = h, best = j;
  }
  EXPECT_EQ(q.NextStimulusIndex(), best);
  // A trial tells something: the expected entropy is below the current one.
  EXPECT_LT(best_h, q.Entropy());
}

TEST(QuestPlus, ReplayReproducesTheIncrementalState) {
  QuestPlus q(Config());
  std::vector<std::pair<double, bool>> h;
  Rng rng(3);
  const SimulatedObserverParams o{
      .shape = Shape::kWeibull, .threshold = 0.2, .slope = 3, .lapse = 0.02};
  for (int i = 0; i < 20; ++i) {
    const double x = q.NextStimulus();
    const bool r = sim::SimulatedAnswer(o, Task::k2Afc, x, 0, rng).positive;
    q.Update(q.StimulusIndex(x), r);
    h.emplace_back(x, r);
  }
  const auto replay = QuestPlus::Replay(Config(), h);
  EXPECT_EQ(replay.posterior(), q.posterior());
  EXPECT_EQ(replay.NextStimulus(), q.NextStimulus());
  EXPECT_THROW(QuestPlus::Replay(Config(), {{0.0123, true}}), InputError);
}

// With a simulated observer whose true parameters lie on the grid, the posterior
// concentrates on them: over 10 seeds of 200 trials the true threshold lies in the central
// 95 % of the threshold marginal in at least 9, the posterior mean is within 3 posterior SDs
// of it, and the posterior SD has shrunk to a third of the prior's or less.
TEST(QuestPlus, PosteriorConcentratesOnTheTrueParameters) {
  QuestPlusConfig c = Config();
  const double true_threshold = c.thresholds[12];  // about 0.19
  const SimulatedObserverParams o{
      .shape = Shape::kWeibull, .threshold = true_threshold, .slope = 3, .lapse = 0.02};
  constexpr int kSeeds = 10, kTrials = 200;
  int covered = 0;
  double prior_mean = 0, prior_var = 0;
  for (double t : c.thresholds) prior_mean += t / static_cast<double>(c.thresholds.size());
  for (double t : c.thresholds)
    prior_var += (t - prior_mean) * (t - prior_mean) / static_cast<double>(c.thresholds.size());
  const double prior_sd = std::sqrt(prior_var);
  for (int s = 0; s < kSeeds; ++s) {
    QuestPlus q(c);
    Rng rng(DeriveSeed(11, static_cast<std::uint64_t>(s)));
    for (int i = 0; i < kTrials; ++i) {
      const std::size_t j = q.NextStimulusIndex();
      q.Update(j, sim::SimulatedAnswer(o, Task::k2Afc, c.stimuli[j], 0, rng).positive);
    }
    const auto m = q.ThresholdMarginal();
    double below = 0;  // posterior mass strictly below the true grid value
    for (std::size_t i = 0; i < 12; ++i) below += m[i];
    covered += below < 0.975 && below + m[12] > 0.025;
    double var = 0;
    for (std::size_t i = 0; i < m.size(); ++i)
      var += m[i] * std::pow(c.thresholds[i] - q.Mean().threshold, 2);
    // Calibrated: the truth within 3 posterior SDs of the mean; concentrated: the posterior SD
    // a third of the prior's or less.
    EXPECT_NEAR(q.Mean().threshold, true_threshold, 3 * std::sqrt(var)) << "seed " << s;
    EXPECT_LT(std::sqrt(var), prior_sd / 3) << "seed " << s;
  }
  EXPECT_GE(covered, 9);
}

}  // namespace
}  // namespace hapticlab::psychophysics::quest_plus_test
