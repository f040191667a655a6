#include "hapticlab/psychophysics/staircase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::psychophysics {

// The "file" of an InputError about replayed trials: the caller knows which database or
// session they came from; the line is the trial's 1-based position in the record.
constexpr const char* kRecordedTrials = "<recorded trials>";

bool StaircaseConfig::IsValid(std::string* why) const {
  std::string w;
  if (up < 1 || down < 1)
    w = "up and down must be >= 1";
  else if (step_sizes.empty() ||
           std::any_of(step_sizes.begin(), step_sizes.end(), [](double s) { return !(s > 0); }))
    w = "step sizes must be > 0";
  else if (start_levels.empty())
    w = "needs at least one start level (one per interleaved track)";
  else if (!(min_level < max_level))
    w = "min_level must be below max_level";
  else if (std::any_of(start_levels.begin(), start_levels.end(),
                       [&](double l) { return !(l >= min_level && l <= max_level); }))
    w = "start levels must lie within [min_level, max_level]";
  else if (step_type == StepType::kLog &&
           (!(min_level > 0) || std::any_of(start_levels.begin(), start_levels.end(),
                                            [](double l) { return !(l > 0); })))
    w = "logarithmic steps need levels > 0 (set min_level > 0)";
  else if (max_reversals < 1 || max_trials < 1)
    w = "max_reversals and max_trials must be >= 1";
  else if (discard_reversals < 0)
    w = "discard_reversals must be >= 0";
  if (why) *why = w;
  return w.empty();
}

namespace {

// Applies one answer to a track (Levitt's transformed up-down rule).
void Step(const StaircaseConfig& c, TrackState& t, bool positive) {
  ++t.trials;
  int move = 0;
  if (positive) {
    t.negative_run = 0;
    if (++t.positive_run >= c.down) move = -1;
  } else {
    t.positive_run = 0;
    if (++t.negative_run >= c.up) move = +1;
  }
  if (move != 0) {
    t.positive_run = t.negative_run = 0;
    if (t.direction != 0 && move != t.direction) t.reversal_levels.push_back(t.level);
    t.direction = move;
    const auto k = std::min(t.reversal_levels.size(), c.step_sizes.size() - 1);
    const double step = c.step_sizes[k];
    const double next = c.step_type == StepType::kLinear ? t.level + move * step
                                                         : t.level * std::pow(10.0, move * step);
    t.level = std::clamp(next, c.min_level, c.max_level);
  }
  t.done =
      static_cast<int>(t.reversal_levels.size()) >= c.max_reversals || t.trials >= c.max_trials;
}

}  // namespace

std::vector<TrackState> ReplayStaircase(const StaircaseConfig& c,
                                        const std::vector<StaircaseTrial>& trials) {
  std::string why;
  HL_REQUIRE(c.IsValid(&why), "staircase: " + why);
  std::vector<TrackState> tracks(c.start_levels.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) tracks[i].level = c.start_levels[i];
  for (std::size_t i = 0; i < trials.size(); ++i) {
    const auto& r = trials[i];
    if (r.track < 0 || r.track >= static_cast<int>(tracks.size()))
      throw InputError(kRecordedTrials, static_cast<int>(i) + 1, "track",
                       fmt::format("0 to {} (got {})", tracks.size() - 1, r.track));
    TrackState& t = tracks[static_cast<std::size_t>(r.track)];
    if (t.done)
      throw InputError(kRecordedTrials, static_cast<int>(i) + 1, "track",
                       fmt::format("a running track (track {} had stopped)", r.track));
    if (std::abs(r.level - t.level) > 1e-9 * std::max(1.0, std::abs(t.level)))
      throw InputError(
          kRecordedTrials, static_cast<int>(i) + 1, "level",
          fmt::format("{} as the staircase's rules give (recorded {})", t.level, r.level));
    Step(c, t, r.positive);
  }
  return tracks;
}

NextStaircaseTrial NextTrial(const StaircaseConfig& c, const std::vector<StaircaseTrial>& trials,
                             std::uint64_t seed) {
  const auto tracks = ReplayStaircase(c, trials);
  std::vector<int> running;
  for (std::size_t i = 0; i < tracks.size(); ++i)
    if (!tracks[i].done) running.push_back(static_cast<int>(i));
  NextStaircaseTrial n;
  if (running.empty()) {
    n.done = true;
    return n;
  }
  Rng rng(DeriveSeed(seed, trials.size()));
  n.track = running[rng.Below(running.size())];
  n.level = tracks[static_cast<std::size_t>(n.track)].level;
  return n;
}

double TrackEstimate(const StaircaseConfig& c, const TrackState& t) {
  const auto& r = t.reversal_levels;
  if (r.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t skip = static_cast<int>(r.size()) > c.discard_reversals
                               ? static_cast<std::size_t>(c.discard_reversals)
                               : 0;
  double s = 0;
  for (std::size_t i = skip; i < r.size(); ++i)
    s += c.step_type == StepType::kLog ? std::log(r[i]) : r[i];
  s /= static_cast<double>(r.size() - skip);
  return c.step_type == StepType::kLog ? std::exp(s) : s;
}

double TargetProbability(int up, int down) {
  // P(m positives in a row before n negatives in a row), runs resetting each other:
  // P = p^(m-1) (1 - q^n) / (p^(m-1) + q^(n-1) - p^(m-1) q^(n-1)), q = 1 - p; increasing in p.
  auto prob_down = [&](double p) {
    const double q = 1 - p, pm = std::pow(p, down - 1), qn = std::pow(q, up - 1);
    return pm * (1 - q * qn) / (pm + qn - pm * qn);
  };
  double lo = 0, hi = 1;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (prob_down(mid) < 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace hapticlab::psychophysics
