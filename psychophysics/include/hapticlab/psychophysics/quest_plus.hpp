#pragma once
/// @file QUEST+ [Watson 2017, "QUEST+: A general multidimensional Bayesian adaptive
/// psychometric method", J. Vision 17(3):10, doi:10.1167/17.3.10] for a binary response and
/// a psychometric function psi(x; threshold, slope, lapse) with a fixed guess rate.
///
/// Domains: stimuli x_j, parameter grid theta = (threshold, slope, lapse) (Cartesian product of
/// the three lists), outcomes r in {negative, positive}. Prior: uniform over the grid.
/// Likelihood table L(r | x, theta) = psi or 1 - psi. After each trial the posterior is
/// multiplied by L(r | x, .) and normalised. The next stimulus minimises the expected entropy
/// of the posterior after the trial:
///   E[H](x) = sum_r P(r | x) H(post_{x,r}),   P(r | x) = sum_theta post(theta) L(r | x, theta),
///   post_{x,r}(theta) = post(theta) L(r | x, theta) / P(r | x),  H(p) = -sum p ln p
/// (Watson's steps 3-5; ties go to the lowest stimulus index).
///
/// The state is a pure function of the recorded trials (`Replay`): a resumed session places
/// exactly the stimuli it would have placed without the interruption.

#include <cstddef>
#include <string>
#include <vector>

#include "hapticlab/psychophysics/psychometric.hpp"

namespace hapticlab::psychophysics {

struct QuestPlusConfig {
  Shape shape = Shape::kWeibull;
  double guess = 0.5;               ///< gamma, from the task
  std::vector<double> stimuli;      ///< stimulus domain (the varied parameter's unit)
  std::vector<double> thresholds;   ///< alpha grid
  std::vector<double> slopes;       ///< beta grid
  std::vector<double> lapses{0.0};  ///< lambda grid
  /// Empty when usable, else why not.
  bool IsValid(std::string* why) const;
};

/// One parameter grid point.
struct QuestPlusPoint {
  double threshold = 0, slope = 0, lapse = 0;
};

class QuestPlus {
 public:
  /// @throws PreconditionError when the configuration is not valid (protocols validate it)
  explicit QuestPlus(QuestPlusConfig c);
  /// Rebuilds the posterior from recorded (stimulus, positive) trials in order.
  /// @throws InputError (file "<recorded trials>", field "stimulus") when a stimulus is not in
  /// the domain; std::runtime_error when an answer has zero probability everywhere
  static QuestPlus Replay(const QuestPlusConfig& c,
                          const std::vector<std::pair<double, bool>>& trials);

  /// Bayes update with one answer at stimulus index j.
  void Update(std::size_t j, bool positive);
  /// Index of the stimulus in the domain (exact match within 1e-12 relative); throws if none.
  std::size_t StimulusIndex(double x) const;
  /// E[H] after a trial at stimulus index j (nats).
  double ExpectedEntropy(std::size_t j) const;
  /// The stimulus index minimising ExpectedEntropy.
  std::size_t NextStimulusIndex() const;
  double NextStimulus() const { return c_.stimuli[NextStimulusIndex()]; }

  const QuestPlusConfig& config() const { return c_; }
  /// Posterior probabilities, indexed [threshold][slope][lapse] flattened (lapse fastest).
  const std::vector<double>& posterior() const { return post_; }
  QuestPlusPoint Point(std::size_t k) const;
  /// Posterior mean of each parameter.
  QuestPlusPoint Mean() const;
  /// Grid point of highest posterior probability.
  QuestPlusPoint Mode() const;
  /// Posterior marginal of the threshold, one value per thresholds[i].
  std::vector<double> ThresholdMarginal() const;
  double Entropy() const;
  int trials() const { return trials_; }

 private:
  QuestPlusConfig c_;
  std::vector<double> post_;
  std::vector<double> psi_;  // psi(x_j; theta_k), [j * K + k]
  int trials_ = 0;
};

}  // namespace hapticlab::psychophysics
