#pragma once
// The Fig. 3.7 comparison on the synthetic AR grids (dissertation ch. III.3; issue #19), shared
// by its test (neural_cv_test.cpp: the asserted seeds) and the exploration program
// bench/neural_fig37.cpp (other seeds, one grid, the per-cell linear part, E_s per condition).

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "neural_fixture.hpp"

namespace hapticlab::modeling {
namespace {

// ArGridRecording: neural_fixture.hpp.
inline std::vector<Recording> ArGrid(bool nonlinear, std::uint64_t seed) {
  std::vector<Recording> recs;
  int k = 0;
  for (const double v : {0.04, 0.06, 0.08, 0.10, 0.12})
    for (const double f : {0.54, 0.89, 1.18, 1.40, 1.91})
      recs.push_back(ArGridRecording(v, f, nonlinear, seed + static_cast<std::uint64_t>(k++)));
  return recs;
}

// Per condition: E_s^2 split by the bands' frequency ranges (sum over the band's Welch bins of
// the squared magnitude difference over the whole measured energy).
inline std::string EsSquaredByBand(const CvRow& row) {
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

// What RunArGrid varies besides the grid and seed (the exploration program's options).
struct Fig37Options {
  bool per_cell = false;  // Γ_U's linear part per cell everywhere (its stability fallback forced)
  bool refit = true;      // NeuralFitOptions::refit_linear_part
  bool rows = false;      // print E_s per condition (LPC and Γ_U)
};

// One AR grid on one data seed, thesis split (train 4, 8, 12 cm/s x 0.54, 1.18, 1.91 N, held
// out 6, 10 cm/s and 0.89, 1.40 N): LPC and Γ_U, Γ_D when `run_d`; prints the table line and
// Γ_U's validation decision.
inline ArGridCv RunArGrid(bool nonlinear, std::uint64_t seed, bool run_d,
                          const Fig37Options& fo = {}) {
  const std::vector<double> tv = {0.04, 0.08, 0.12}, tf = {0.54, 1.18, 1.91};
  const auto recs = ArGrid(nonlinear, seed);
  ArGridCv out;
  out.lpc = CrossValidate(recs, tv, tf, {});
  auto uo = Quick(renderer::NeuralTopology::kUnified);
  if (fo.per_cell) uo.max_condition_basis_radius = 0;
  uo.refit_linear_part = fo.refit;
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
  if (fo.rows)
    for (std::size_t r = 0; r < out.u.rows.size(); ++r)
      std::printf("  %s %.2f m/s %.2f N: LPC %.3f, Γ_U %.3f | E_s^2 by band LPC %s, Γ_U %s\n",
                  out.u.rows[r].train ? "train" : "cv   ", out.u.rows[r].speed_mps,
                  out.u.rows[r].force_N, out.lpc.rows[r].es, out.u.rows[r].es,
                  EsSquaredByBand(out.lpc.rows[r]).c_str(), EsSquaredByBand(out.u.rows[r]).c_str());
  return out;
}

}  // namespace
}  // namespace hapticlab::modeling
