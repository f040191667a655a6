// The Fig. 3.7 comparison (dissertation ch. III.3; issue #19) of LPC, Γ_U and Γ_D by
// cross-validation (modeling/src/neural_cv.cpp): on synthetic textures and on the linear and
// nonlinear AR grids, trained and held out.

#include <gtest/gtest.h>

#include <array>

#include "neural_fig37.hpp"

namespace hapticlab::modeling::neural_cv_test {
namespace {

// Fig. 3.7 on synthetic textures: training and cross-validation E_s of LPC, Γ_U and Γ_D on the
// thesis's grid (train v = 4, 8, 12 cm/s x f = 0.54, 1.18, 1.91 N; held out 6, 10 cm/s x
// 0.89, 1.40 N).
TEST(NeuralFig37, LpcUnifiedAndDecomposedOnOneTable) {
  const std::vector<double> tv = {0.04, 0.08, 0.12}, tf = {0.54, 1.18, 1.91};
  struct Row {
    double period_m, lpc_tr, lpc_cv, u_tr, u_cv, d_tr, d_cv;
  };
  std::vector<Row> rows;
  for (const double period : {0.2e-3, 0.35e-3, 0.5e-3}) {
    const auto recs = TextureGrid(period, 11);
    const auto lpc = CrossValidate(recs, tv, tf, {});
    const auto u = CrossValidateNeural(recs, tv, tf, Quick(renderer::NeuralTopology::kUnified));
    const auto d = CrossValidateNeural(recs, tv, tf, Quick(renderer::NeuralTopology::kDecomposed));
    rows.push_back({period, lpc.mean_es_train, lpc.mean_es_test, u.mean_es_train, u.mean_es_test,
                    d.mean_es_train, d.mean_es_test});
  }
  std::printf("texture period | LPC train  cv | Γ_U train  cv | Γ_D train  cv   (mean E_s)\n");
  for (const auto& r : rows) {
    std::printf("  %.2f mm      |  %.3f  %.3f |  %.3f  %.3f |  %.3f  %.3f\n", r.period_m * 1e3,
                r.lpc_tr, r.lpc_cv, r.u_tr, r.u_cv, r.d_tr, r.d_cv);
    for (const double e : {r.lpc_tr, r.lpc_cv, r.u_tr, r.u_cv, r.d_tr, r.d_cv}) EXPECT_LT(e, 0.5);
    // These textures are close to a linear process driven by noise (LPC's home ground): the
    // unified network must come as close to LPC held out as on the linear AR grid (issue #19).
    EXPECT_LE(r.u_cv, r.lpc_cv + 0.1);
  }
}

// Fig. 3.7 on the synthetic AR grids: LPC, Γ_U, Γ_D, training and held-out mean E_s, and issue
// #19's targets.
// Linear grid, data seeds 40 and 41, each seed: Γ_U within 0.05 of LPC on training conditions
// and within 0.1 held out (met with margin on all eight seeds measured, 40-43 and 50-53).
// Nonlinear grid, data seeds 40-43: Γ_U within 0.02 of LPC on training conditions on each
// seed, and "Γ_U below LPC held out" as a paired comparison over the four seeds: the mean of
// (Γ_U cv - LPC cv) below 0 and Γ_U below LPC on at least 3 of the 4 (three quarters of the
// seeds run, rounded up, in bench/neural_fig37 with other seeds). Why paired: the target is a claim
// about the model, and one 2.5 s realization decides one seed. Seed 42 is included and is above LPC
// (+0.011): its gap is one held-out condition, 10 cm/s 0.54 N, where band 2's biquadratic AR
// interpolates to a too-sharp resonance (pole radius 0.993, E_s 0.741 against LPC's 0.270);
// LPC's own interpolation of per-cell fits was tried and is worse (docs/modeling-neural.md).
// Measured: below LPC on 7 of 8 realizations (40-43, 50-53), mean -0.021 over 40-43.
// Γ_D (printed, not asserted) runs on the first seed of each grid only: it costs about two Γ_U
// runs.
TEST(NeuralFig37, LinearAndNonlinearArGrids) {
  std::printf("AR grid, seed | LPC train  cv | Γ_U train  cv | Γ_D train  cv   (mean E_s)\n");
  for (const std::uint64_t seed : std::vector<std::uint64_t>{40, 41}) {
    const auto cv = RunArGrid(false, seed, seed == 40);
    EXPECT_LE(cv.u.mean_es_train, cv.lpc.mean_es_train + 0.05) << "linear grid, seed " << seed;
    EXPECT_LE(cv.u.mean_es_test, cv.lpc.mean_es_test + 0.1) << "linear grid, seed " << seed;
  }
  const std::vector<std::uint64_t> seeds = {40, 41, 42, 43};
  std::string diffs;
  double sum = 0;
  std::size_t below = 0;
  for (const std::uint64_t seed : seeds) {
    const auto cv = RunArGrid(true, seed, seed == seeds.front());
    EXPECT_LE(cv.u.mean_es_train, cv.lpc.mean_es_train + 0.02) << "nonlinear grid, seed " << seed;
    const double diff = cv.u.mean_es_test - cv.lpc.mean_es_test;
    sum += diff;
    if (diff < 0) ++below;
    diffs += fmt::format("{}{}: {:+.3f}", diffs.empty() ? "" : ", ", seed, diff);
  }
  const double mean = sum / static_cast<double>(seeds.size());
  std::printf(
      "nonlinear grid, Γ_U cv - LPC cv by data seed: %s; mean %+.3f; Γ_U below LPC on %zu "
      "of %zu (3 asserted)\n",
      diffs.c_str(), mean, below, seeds.size());
  EXPECT_LT(mean, 0.0) << diffs;
  EXPECT_GE(below, 3u) << diffs;
}
}  // namespace
}  // namespace hapticlab::modeling::neural_cv_test
