// Issue #33: Γ_U's linear part is stable over the whole condition range. The pole radius
// against closed forms, the condition basis sized to the grid, and on generated AR grids of
// 2 x 2, 3 x 2 and 3 x 3 training conditions with whole speed rows held out: every band's
// largest pole radius over the hull below 1 and the held-out E_s within 0.1 of LPC's.

#include <gtest/gtest.h>

#include <chrono>
#include <mutex>

#include "../../modeling/src/neural_internal.hpp"
#include "hapticlab/modeling/cross_validation.hpp"
#include "neural_fixture.hpp"

namespace hapticlab::modeling::neural_stability_test {
namespace {

using neural_internal::ActiveConditionTerms;
using neural_internal::MaxPoleRadius;

// Closed forms: AR(1) c = {p} has its pole at p; a resonance 2 r cos(th), -r^2 has two at
// radius r; the product of two resonances has the larger radius of the two.
TEST(NeuralStability, MaxPoleRadiusMatchesClosedForms) {
  EXPECT_NEAR(MaxPoleRadius(std::vector<double>{0.7}), 0.7, 1e-9);
  EXPECT_NEAR(MaxPoleRadius(std::vector<double>{-1.3}), 1.3, 1e-9);
  for (const double r : {0.5, 0.95, 1.0, 1.18}) {
    const double th = 0.4;
    EXPECT_NEAR(MaxPoleRadius(std::vector<double>{2 * r * std::cos(th), -r * r}), r, 1e-9) << r;
  }
  const double a1 = 2 * 0.9 * std::cos(0.3), a2 = -0.81, b1 = 2 * 1.02 * std::cos(1.1),
               b2 = -1.02 * 1.02;
  const std::vector<double> c = {a1 + b1, a2 + b2 - a1 * b1, -a1 * b2 - a2 * b1, -a2 * b2};
  EXPECT_NEAR(MaxPoleRadius(c), 1.02, 1e-9);
  EXPECT_EQ(MaxPoleRadius(std::vector<double>{}), 0.0);
}

TEST(NeuralStability, TheConditionBasisHasNoMoreTermsThanTheGridHasNodes) {
  auto count = [](std::size_t nv, std::size_t nf) {
    const auto on = ActiveConditionTerms(nv, nf);
    return std::count(on.begin(), on.end(), true);
  };
  EXPECT_EQ(count(2, 2), 4);  // 1, v, f, v f: bilinear, exact on the four corners
  EXPECT_EQ(count(3, 2), 6);
  EXPECT_EQ(count(2, 3), 6);
  EXPECT_EQ(count(3, 3), 9);
  EXPECT_EQ(count(5, 5), 9);
  EXPECT_EQ(count(1, 3), 3);
  // On 2 x 2 the terms are those of degree <= 1 in each variable.
  const auto on = ActiveConditionTerms(2, 2);
  EXPECT_TRUE(on[0] && on[1] && on[2] && on[4]);
  EXPECT_FALSE(on[3] || on[5] || on[6] || on[7] || on[8]);
}

// NeuralMaxPoleRadius against a closed form: an AR(1) linear part c_1 = 0.5 + 0.6 v' has its
// pole at 0.5 + 0.6 v', largest (1.1) at the grid's top speed, whatever the force.
TEST(NeuralStability, HullRadiusFindsTheWorstConditionOfAModel) {
  renderer::NeuralModel m;
  m.speeds_mps = {0.04, 0.12};
  m.forces_N = {0.5, 2.0};
  renderer::NeuralBand b;
  b.lo_hz = 20, b.hi_hz = 900, b.decimation = 1, b.history = 1;
  renderer::NeuralNet n{{3, 1}, std::vector<double>(4, 0.0), std::vector<double>(9, 0.0)};
  n.linear[0] = 0.5;
  n.linear[1] = 0.6;  // the v' term
  b.nets = {n};
  b.sigma.assign(4, 0.1);
  m.bands = {b};
  const auto hull = NeuralMaxPoleRadius(m, 0);
  EXPECT_NEAR(hull.radius, 1.1, 1e-9);
  EXPECT_NEAR(hull.speed_mps, 0.12, 1e-12);
  m.bands[0].nets[0].linear[1] = -0.3;  // 0.8 at the lowest speed
  EXPECT_NEAR(NeuralMaxPoleRadius(m, 0).radius, 0.8, 1e-9);
  EXPECT_NEAR(NeuralMaxPoleRadius(m, 0).speed_mps, 0.04, 1e-12);
}

// The evidence of issue #33 on the linear AR grid (neural_fixture.hpp ArGridRecording, data
// seed 60): Γ_U fitted on 2 x 2, 3 x 2 and 3 x 3 training grids, every recording at the other
// speeds (whole rows) held out. Small networks and 1.5 s recordings keep it to seconds; the
// linear part is what the assertions are about.
TEST(NeuralStability, GammaUIsStableOverTheHullAndHoldsOutWholeSpeedRows) {
  struct Grid {
    std::vector<double> v, f;
  };
  const Grid grids[] = {{{0.04, 0.12}, {0.54, 1.91}},
                        {{0.04, 0.08, 0.12}, {0.54, 1.91}},
                        {{0.04, 0.08, 0.12}, {0.54, 1.18, 1.91}}};
  NeuralFitOptions o = Quick(renderer::NeuralTopology::kUnified);
  o.train.max_epochs = 5;
  o.hidden_large = {8, 4};
  for (auto& b : o.bands) b.history = 20;
  for (const auto& g : grids) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Recording> all, train;
    std::uint64_t seed = 60;
    for (const double v : {0.04, 0.06, 0.08, 0.10, 0.12})
      for (const double f : g.f) {
        all.push_back(ArGridRecording(v, f, false, seed++, 1.5));
        if (NearAny(g.v, v)) train.push_back(all.back());
      }
    const std::string grid = fmt::format("{} x {}", g.v.size(), g.f.size());
    const auto model = FitNeural(train, o);
    for (std::size_t b = 0; b < model.bands.size(); ++b) {
      const auto hull = NeuralMaxPoleRadius(model, b);
      std::printf("%s grid, band %zu: largest pole radius %.4f (at %.3f m/s, %.2f N)\n",
                  grid.c_str(), b + 1, hull.radius, hull.speed_mps, hull.force_N);
      EXPECT_LT(hull.radius, 1.0) << grid << ", band " << b + 1;
    }
    // Held-out E_s as CrossValidateNeural computes it, on the same fit.
    double es = 0;
    int held = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (NearAny(g.v, all[i].speed_mps)) continue;
      const auto measured = Preprocess(all[i], o.preprocess);
      es += SpectralError(measured, SynthesizeNeural(model, all[i].speed_mps, all[i].force_N,
                                                     measured.size(), 1 + i));
      ++held;
    }
    es /= held;
    const auto lpc = CrossValidate(all, g.v, g.f, {});
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s grid, %d held-out recordings: E_s Γ_U %.3f, LPC %.3f (%.1f s)\n", grid.c_str(),
                held, es, lpc.mean_es_test, s);
    EXPECT_LE(es, lpc.mean_es_test + 0.1) << grid;
  }
}

// Issue #33: Γ_U's per-cell fallback, forced by a pole-radius limit of 0 that no condition basis
// meets. Every band is then one AR fit per training cell (each minimum phase) mixed in LSF form,
// with no condition-basis weights; the hull's largest radius is below 1; each band's progress
// names the fallback; and the model plays the training conditions within 0.1 E_s of the LPC
// bank (its linear part is the bank's interpolation). With the default limit the same data keep
// the condition basis, so the fallback above was forced, not taken anyway. The recordings are
// uncalibrated, and the model says so.
TEST(NeuralStability, PerCellFallbackTakesOverWhereTheConditionBasisMissesItsLimit) {
  std::vector<Recording> recs;
  std::uint64_t seed = 80;
  for (const double v : {0.04, 0.12})
    for (const double f : {0.54, 1.91}) recs.push_back(ArGridRecording(v, f, false, seed++, 1.5));
  for (auto& r : recs) r.calibrated = false;  // in the sensor's units: the model file says so
  NeuralFitOptions o = Quick(renderer::NeuralTopology::kUnified);
  o.train.max_epochs = 5;
  o.hidden_large = {8, 4};
  for (auto& b : o.bands) b.history = 20;
  o.max_condition_basis_radius = 0;
  std::mutex mu;
  int fallbacks = 0;
  o.progress = [&](const std::string& what, int, int) {
    const std::lock_guard<std::mutex> lock(mu);
    fallbacks += what.find("fitted per cell") != std::string::npos;
  };
  const auto m = FitNeural(recs, o);
  EXPECT_EQ(fallbacks, static_cast<int>(m.bands.size()));
  EXPECT_FALSE(m.calibrated);
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    ASSERT_EQ(m.bands[b].cell_ar.size(), 4u) << "band " << b + 1;
    for (const auto& a : m.bands[b].cell_ar) EXPECT_TRUE(renderer::IsStableAr(a)) << b + 1;
    for (const auto& n : m.bands[b].nets) EXPECT_TRUE(n.linear.empty()) << b + 1;
    EXPECT_LT(NeuralMaxPoleRadius(m, b).radius, 1.0) << "band " << b + 1;
  }
  double es = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const auto measured = Preprocess(recs[i], o.preprocess);
    es += SpectralError(measured, SynthesizeNeural(m, recs[i].speed_mps, recs[i].force_N,
                                                   measured.size(), 1 + i)) /
          static_cast<double>(recs.size());
  }
  const auto lpc = CrossValidate(recs, {0.04, 0.12}, {0.54, 1.91}, {});
  EXPECT_LE(es, lpc.mean_es_train + 0.1) << "LPC " << lpc.mean_es_train;
  o.max_condition_basis_radius = 1;
  o.progress = nullptr;
  for (const auto& b : FitNeural(recs, o).bands) EXPECT_TRUE(b.cell_ar.empty());
}

}  // namespace
}  // namespace hapticlab::modeling::neural_stability_test
