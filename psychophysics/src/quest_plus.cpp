#include "hapticlab/psychophysics/quest_plus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::psychophysics {

// The "file" of an InputError about replayed trials: the caller knows which database or
// session they came from; the line is the trial's 1-based position in the record.
constexpr const char* kRecordedTrials = "<recorded trials>";

bool QuestPlusConfig::IsValid(std::string* why) const {
  std::string w;
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  if (stimuli.empty() || thresholds.empty() || slopes.empty() || lapses.empty())
    w = "stimuli, thresholds, slopes and lapses must each have at least one value";
  else if (!finite(stimuli) || !finite(thresholds) || !finite(slopes) || !finite(lapses))
    w = "values must be finite";
  else if (!(guess >= 0 && guess < 1))
    w = "guess rate must be in [0, 1)";
  else if (std::any_of(lapses.begin(), lapses.end(),
                       [&](double l) { return !(l >= 0 && l < 1 - guess); }))
    w = "lapse rates must be in [0, 1 - guess)";
  else if (std::any_of(slopes.begin(), slopes.end(), [](double b) { return !(b > 0); }))
    w = "slopes must be > 0";
  else if (shape == Shape::kWeibull &&
           (std::any_of(stimuli.begin(), stimuli.end(), [](double x) { return !(x > 0); }) ||
            std::any_of(thresholds.begin(), thresholds.end(), [](double x) { return !(x > 0); })))
    w = "a Weibull needs stimuli and thresholds > 0";
  if (why) *why = w;
  return w.empty();
}

QuestPlus::QuestPlus(QuestPlusConfig c) : c_(std::move(c)) {
  std::string why;
  HL_REQUIRE(c_.IsValid(&why), "QUEST+: " + why);
  const std::size_t K = c_.thresholds.size() * c_.slopes.size() * c_.lapses.size();
  post_.assign(K, 1.0 / static_cast<double>(K));
  psi_.resize(c_.stimuli.size() * K);
  for (std::size_t j = 0; j < c_.stimuli.size(); ++j)
    for (std::size_t k = 0; k < K; ++k) {
      const auto th = Point(k);
      psi_[j * K + k] = Psi(c_.shape, c_.stimuli[j], {th.threshold, th.slope, c_.guess, th.lapse});
    }
}

QuestPlus QuestPlus::Replay(const QuestPlusConfig& c,
                            const std::vector<std::pair<double, bool>>& trials) {
  QuestPlus q(c);
  for (const auto& [x, r] : trials) q.Update(q.StimulusIndex(x), r);
  return q;
}

QuestPlusPoint QuestPlus::Point(std::size_t k) const {
  const std::size_t nl = c_.lapses.size(), ns = c_.slopes.size();
  return {c_.thresholds[k / (nl * ns)], c_.slopes[(k / nl) % ns], c_.lapses[k % nl]};
}

std::size_t QuestPlus::StimulusIndex(double x) const {
  for (std::size_t j = 0; j < c_.stimuli.size(); ++j)
    if (std::abs(c_.stimuli[j] - x) <= 1e-12 * std::max(1.0, std::abs(x))) return j;
  throw InputError(kRecordedTrials, 0, "stimulus",
                   fmt::format("a value of the QUEST+ stimulus domain (got {})", x));
}

void QuestPlus::Update(std::size_t j, bool positive) {
  const std::size_t K = post_.size();
  double sum = 0;
  for (std::size_t k = 0; k < K; ++k) {
    const double L = positive ? psi_[j * K + k] : 1 - psi_[j * K + k];
    post_[k] *= L;
    sum += post_[k];
  }
  if (!(sum > 0))
    throw std::runtime_error("QUEST+: the answer has zero probability under every grid point");
  for (auto& p : post_) p /= sum;
  ++trials_;
}

double QuestPlus::ExpectedEntropy(std::size_t j) const {
  const std::size_t K = post_.size();
  // Unnormalised posteriors u_r = post * L_r; P(r) = sum u_r; H(u_r / P(r)) =
  // ln P(r) - sum u_r ln u_r / P(r). So E[H] = sum_r (P(r) ln P(r) - sum u_r ln u_r).
  double p1 = 0, s1 = 0, p0 = 0, s0 = 0;
  for (std::size_t k = 0; k < K; ++k) {
    const double u1 = post_[k] * psi_[j * K + k], u0 = post_[k] * (1 - psi_[j * K + k]);
    p1 += u1;
    p0 += u0;
    if (u1 > 0) s1 += u1 * std::log(u1);
    if (u0 > 0) s0 += u0 * std::log(u0);
  }
  double eh = 0;
  if (p1 > 0) eh += p1 * std::log(p1) - s1;
  if (p0 > 0) eh += p0 * std::log(p0) - s0;
  return eh;
}

std::size_t QuestPlus::NextStimulusIndex() const {
  std::size_t best = 0;
  double best_h = ExpectedEntropy(0);
  for (std::size_t j = 1; j < c_.stimuli.size(); ++j) {
    const double h = ExpectedEntropy(j);
    if (h < best_h) best_h = h, best = j;
  }
  return best;
}

QuestPlusPoint QuestPlus::Mean() const {
  QuestPlusPoint m;
  for (std::size_t k = 0; k < post_.size(); ++k) {
    const auto p = Point(k);
    m.threshold += post_[k] * p.threshold;
    m.slope += post_[k] * p.slope;
    m.lapse += post_[k] * p.lapse;
  }
  return m;
}

QuestPlusPoint QuestPlus::Mode() const {
  return Point(
      static_cast<std::size_t>(std::max_element(post_.begin(), post_.end()) - post_.begin()));
}

std::vector<double> QuestPlus::ThresholdMarginal() const {
  std::vector<double> m(c_.thresholds.size(), 0.0);
  const std::size_t per = c_.slopes.size() * c_.lapses.size();
  for (std::size_t k = 0; k < post_.size(); ++k) m[k / per] += post_[k];
  return m;
}

double QuestPlus::Entropy() const {
  double h = 0;
  for (double p : post_)
    if (p > 0) h -= p * std::log(p);
  return h;
}

}  // namespace hapticlab::psychophysics
