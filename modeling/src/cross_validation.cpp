#include "hapticlab/modeling/cross_validation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::modeling {

bool NearAny(const std::vector<double>& set, double x) {
  return std::any_of(set.begin(), set.end(), [&](double s) {
    return std::abs(s - x) <= 1e-6 * std::max(1.0, std::abs(s));
  });
}

CvResult CrossValidateModel(const std::vector<Recording>& recs, const std::vector<double>& tv,
                            const std::vector<double>& tf, const VibrationFitOptions& preprocess,
                            const CvFit& fit, std::uint64_t seed) {
  RequireConditions(recs, "cv-vibration");
  auto training = [&](const Recording& r) {
    return NearAny(tv, r.speed_mps) && NearAny(tf, r.force_N);
  };
  std::vector<Recording> train;
  for (const auto& r : recs)
    if (training(r)) train.push_back(r);
  if (train.size() < 3)
    throw InputError("<command line>", 0, "training conditions",
                     fmt::format("at least 3 recordings at the training speeds x forces, found {}",
                                 train.size()));
  const ConditionSynthesizer synthesize = fit(train);
  CvResult res;
  int ntr = 0, nte = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const auto& r = recs[i];
    const auto measured = Preprocess(r, preprocess);
    const auto s = synthesize(r, measured.size(), seed + i);
    CvRow row{r.speed_mps,
              r.force_N,
              training(r),
              SpectralError(measured, s),
              WelchMagnitude(measured),
              WelchMagnitude(s)};
    (row.train ? res.mean_es_train : res.mean_es_test) += row.es;
    (row.train ? ntr : nte)++;
    res.rows.push_back(row);
  }
  if (ntr) res.mean_es_train /= ntr;
  if (nte) res.mean_es_test /= nte;
  return res;
}

}  // namespace hapticlab::modeling
