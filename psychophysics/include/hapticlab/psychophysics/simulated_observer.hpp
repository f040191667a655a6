#pragma once
/// @file The parameters of a simulated observer with a known psychometric function on the
/// varied parameter, as a protocol's adaptive phase declares them. The observer that answers
/// with them is sim::SimulatedAnswer (sim/psychophysical_observer.hpp): simulation lives in
/// sim/, above the rig's ground truth; the parameters stay here because protocols (below sim)
/// hold them.

#include "hapticlab/psychophysics/psychometric.hpp"

namespace hapticlab::psychophysics {

struct SimulatedObserverParams {
  Shape shape = Shape::kWeibull;
  double threshold = 1;    ///< alpha, in the varied parameter's unit
  double slope = 3;        ///< beta
  double lapse = 0;        ///< lambda (dimensionless)
  double false_alarm = 0;  ///< yes/no guess rate (dimensionless)
};

}  // namespace hapticlab::psychophysics
