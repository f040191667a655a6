// Evaluating a fitted neural model: free-running synthesis at one condition and the
// leave-conditions-out cross-validation of the fit (cross_validation.hpp), as for the LPC bank.
#include <algorithm>
#include <memory>

#include "hapticlab/modeling/cross_validation.hpp"
#include "hapticlab/modeling/neural.hpp"

namespace hapticlab::modeling {

std::vector<double> SynthesizeNeural(const renderer::NeuralModel& m, double v, double f,
                                     std::size_t n, std::uint64_t seed, std::size_t settle) {
  renderer::NeuralSynth s(std::make_shared<renderer::NeuralModel>(m), seed);
  const double vs = std::max(v, m.min_speed_mps);
  for (std::size_t k = 0; k < settle; ++k) s.Step(vs, f, true);
  std::vector<double> out(n);
  for (auto& x : out) x = s.Step(vs, f, true);
  return out;
}

CvResult CrossValidateNeural(const std::vector<Recording>& recs, const std::vector<double>& tv,
                             const std::vector<double>& tf, const NeuralFitOptions& o,
                             std::uint64_t seed) {
  return CrossValidateModel(
      recs, tv, tf, o.preprocess,
      [&](const std::vector<Recording>& train) -> ConditionSynthesizer {
        // Several recordings of one condition train as one (FitNeural takes one per cell).
        auto model =
            std::make_shared<const renderer::NeuralModel>(FitNeural(PoolByCondition(train), o));
        return [model](const Recording& r, std::size_t n, std::uint64_t s) {
          return SynthesizeNeural(*model, r.speed_mps, r.force_N, n, s);
        };
      },
      seed);
}

}  // namespace hapticlab::modeling
