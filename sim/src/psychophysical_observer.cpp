#include "hapticlab/sim/psychophysical_observer.hpp"

namespace hapticlab::sim {

using psychophysics::Task;

double PositiveProbability(const psychophysics::SimulatedObserverParams& o, Task task, double x) {
  return psychophysics::Psi(
      o.shape, x, {o.threshold, o.slope, psychophysics::GuessRate(task, o.false_alarm), o.lapse});
}

ObserverAnswer SimulatedAnswer(const psychophysics::SimulatedObserverParams& o, Task task, double x,
                               int comparison_interval, Rng& rng) {
  ObserverAnswer a;
  a.positive = rng.Uniform() < PositiveProbability(o, task, x);
  if (task == Task::kYesNo) {
    a.response = a.positive ? 1 : 0;
    return a;
  }
  const int m = psychophysics::Intervals(task);
  if (a.positive) {
    a.response = comparison_interval;
  } else {
    // One of the other m - 1 intervals, uniformly.
    const int k = static_cast<int>(rng.Below(static_cast<std::uint64_t>(m - 1)));
    a.response = k < comparison_interval ? k : k + 1;
  }
  return a;
}

}  // namespace hapticlab::sim
