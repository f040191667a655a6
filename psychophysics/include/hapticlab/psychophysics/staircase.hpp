#pragma once
/// @file Transformed up-down staircases [Levitt 1971, doi:10.1121/1.1912375]: n-up/m-down
/// (the level goes down, i.e. gets harder, after m consecutive positive answers and up after n
/// consecutive negative ones; 1-up-2-down converges on the 70.7 % point, 1-up-3-down on
/// 79.4 %), linear or logarithmic steps whose size may shrink after given numbers of
/// reversals, level bounds, and several interleaved tracks picked at random each trial.
///
/// The state is a pure function of the recorded trials: `ReplayStaircase` rebuilds it from
/// the answers alone (and checks that each recorded level is the one the rules give), so a
/// resumed session continues exactly where it stopped.

#include <cstdint>
#include <string>
#include <vector>

namespace hapticlab::psychophysics {

enum class StepType {
  kLinear,  ///< level +- step (the level's unit)
  kLog,     ///< level * or / 10^step (step in log10 units; levels > 0)
};

struct StaircaseConfig {
  int up = 1;    ///< consecutive negative answers before the level goes up (n)
  int down = 2;  ///< consecutive positive answers before the level goes down (m)
  StepType step_type = StepType::kLinear;
  /// Step used after k reversals is step_sizes[min(k, size - 1)]; must be > 0.
  std::vector<double> step_sizes{0.1};
  /// One start level per interleaved track (>= 1 track).
  std::vector<double> start_levels{1.0};
  double min_level = -1e300, max_level = 1e300;  ///< the level is clamped to these
  int max_reversals = 12;                        ///< a track stops after this many reversals
  int max_trials = 80;                           ///< ... or this many trials
  int discard_reversals = 4;  ///< the estimate averages the reversals after these
  /// Empty when usable, else why not.
  bool IsValid(std::string* why) const;
};

/// One answered trial of a staircase session.
struct StaircaseTrial {
  int track = 0;
  double level = 0;       ///< the comparison level presented
  bool positive = false;  ///< correct (m-AFC) or "yes" (yes/no)
};

/// State of one track after its recorded trials.
struct TrackState {
  double level = 0;  ///< level of the track's next trial
  int trials = 0;
  int positive_run = 0, negative_run = 0;
  int direction = 0;                    ///< last move: +1 up, -1 down, 0 none yet
  std::vector<double> reversal_levels;  ///< level at each reversal, in order
  bool done = false;
};

/// Rebuilds every track from the recorded trials (in order).
/// @throws InputError (file "<recorded trials>", line = the trial's 1-based position) when a
/// recorded level differs (by more than 1e-9 relative) from the one the rules give, or a
/// track index is out of range: the record does not belong to this configuration;
/// PreconditionError when the configuration is not valid (protocols validate it).
std::vector<TrackState> ReplayStaircase(const StaircaseConfig& c,
                                        const std::vector<StaircaseTrial>& trials);

struct NextStaircaseTrial {
  bool done = false;  ///< every track has stopped
  int track = 0;
  double level = 0;
};
/// The next trial after `trials`: a track chosen uniformly among those still running, from a
/// generator seeded by (seed, number of trials so far), so the choice is reproducible.
NextStaircaseTrial NextTrial(const StaircaseConfig& c, const std::vector<StaircaseTrial>& trials,
                             std::uint64_t seed);

/// Threshold estimate of a track: the mean (log steps: geometric mean) of its reversal levels
/// after the first `discard_reversals` (all of them when there are not more than that).
/// nullopt-like NaN when the track has no reversal.
double TrackEstimate(const StaircaseConfig& c, const TrackState& t);

/// The probability of a positive answer an n-up/m-down rule converges on: the p at which a
/// run of m positives (a down-move) comes before a run of n negatives (an up-move) with
/// probability 1/2 [Levitt 1971]. 1-up-2-down: sqrt(1/2) = 0.7071; 1-up-3-down: 0.7937.
double TargetProbability(int up, int down);

}  // namespace hapticlab::psychophysics
