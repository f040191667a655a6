#include "hapticlab/psychophysics/simulated_observer.hpp"

namespace hapticlab::psychophysics {

double PositiveProbability(const SimulatedObserverParams& o, Task task, double x) {
  return Psi(o.shape, x, {o.threshold, o.slope, GuessRate(task, o.false_alarm), o.lapse});
}

ObserverAnswer SimulatedAnswer(const SimulatedObserverParams& o, Task task, double x,
                               int comparison_interval, Rng& rng) {
  ObserverAnswer a;
  a.positive = rng.Uniform() < PositiveProbability(o, task, x);
  if (task == Task::kYesNo) {
    a.response = a.positive ? 1 : 0;
    return a;
  }
  const int m = Intervals(task);
  if (a.positive) {
    a.response = comparison_interval;
  } else {
    // One of the other m - 1 intervals, uniformly.
    const int k = static_cast<int>(rng.Below(static_cast<std::uint64_t>(m - 1)));
    a.response = k < comparison_interval ? k : k + 1;
  }
  return a;
}

}  // namespace hapticlab::psychophysics
