#pragma once
/// @file A simulated observer with a known psychometric function on the varied parameter:
/// the ground truth that makes the adaptive path (staircase, QUEST+, fit, report) testable.
/// In an m-AFC trial it picks the comparison's interval with probability
/// psi(x) = 1/m + (1 - 1/m - lapse) F(x; threshold, slope), otherwise one of the other
/// intervals at random; in yes/no it says "yes" with psi(x) = fa + (1 - fa - lapse) F(x).
/// x is the stimulus variable of the phase (comparison - reference, or the level itself in
/// detection; docs/psychophysics.md).

#include "hapticlab/core/rng.hpp"
#include "hapticlab/psychophysics/psychometric.hpp"

namespace hapticlab::psychophysics {

struct SimulatedObserverParams {
  Shape shape = Shape::kWeibull;
  double threshold = 1;    ///< alpha, in the varied parameter's unit
  double slope = 3;        ///< beta
  double lapse = 0;        ///< lambda (dimensionless)
  double false_alarm = 0;  ///< yes/no guess rate (dimensionless)
};

struct ObserverAnswer {
  int response = 0;       ///< m-AFC: chosen interval (0-based); yes/no: 1 yes, 0 no
  bool positive = false;  ///< correct (m-AFC) or yes (yes/no)
};

/// The probability of a positive answer at x.
double PositiveProbability(const SimulatedObserverParams& o, Task task, double x);

/// One answer. `comparison_interval` is where the comparison was (m-AFC; ignored in yes/no).
ObserverAnswer SimulatedAnswer(const SimulatedObserverParams& o, Task task, double x,
                               int comparison_interval, Rng& rng);

}  // namespace hapticlab::psychophysics
