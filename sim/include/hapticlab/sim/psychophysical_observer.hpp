#pragma once
/// @file The simulated observer of adaptive trials: answers with a known psychometric function
/// on the varied parameter, the ground truth that makes the adaptive path (staircase, QUEST+,
/// fit, report) testable. In an m-AFC trial it picks the comparison's interval with probability
/// psi(x) = 1/m + (1 - 1/m - lapse) F(x; threshold, slope), otherwise one of the other
/// intervals at random; in yes/no it says "yes" with psi(x) = fa + (1 - fa - lapse) F(x).
/// x is the stimulus variable of the phase (comparison - reference, or the level itself in
/// detection; docs/psychophysics.md). Its parameters (psychophysics::SimulatedObserverParams)
/// are declared by a protocol's adaptive phase; the rater of rated trials is sim::Observer
/// (sim_lab.hpp).

#include "hapticlab/core/rng.hpp"
#include "hapticlab/psychophysics/psychometric.hpp"
#include "hapticlab/psychophysics/simulated_observer.hpp"

namespace hapticlab::sim {

struct ObserverAnswer {
  int response = 0;       ///< m-AFC: chosen interval (0-based); yes/no: 1 yes, 0 no
  bool positive = false;  ///< correct (m-AFC) or yes (yes/no)
};

/// The probability of a positive answer at x.
double PositiveProbability(const psychophysics::SimulatedObserverParams& o,
                           psychophysics::Task task, double x);

/// One answer. `comparison_interval` is where the comparison was (m-AFC; ignored in yes/no).
ObserverAnswer SimulatedAnswer(const psychophysics::SimulatedObserverParams& o,
                               psychophysics::Task task, double x, int comparison_interval,
                               Rng& rng);

}  // namespace hapticlab::sim
