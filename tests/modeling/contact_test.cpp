// Contact identification (one engine for `model fit-contact` and the workbench) on free-hand
// measurements generated here: strokes in every direction along curved paths with hand tremor
// at rest, pauses, lift-offs and pokes; Hunt-Crossley normal law; vector Dahl friction with a
// viscous term (eqs. 4.6-4.7) integrated by explicit Euler substeps; force noise 4-12 mN. The
// generator (contact_freehand.hpp) is written for these tests and shares nothing with
// modeling/src/workbench_sim.cpp or the workbench's replay. The command line:
// tests/apps/cmd_model_contact_test.cpp.

#include "hapticlab/modeling/contact.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>

#include "contact_freehand.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/force.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::contact_test {
namespace {

TEST(ContactFreeHand, EveryParameterRecoveredWithUsableFits) {
  const Truth t;
  const auto m = FreeHand(t, 11, 60, 0.008, true);
  const auto f = FitContact(m);
  EXPECT_TRUE(f.IsUsable()) << wb::TerminationText(f.friction_summary) << " / "
                            << wb::TerminationText(f.normal_summary);
  EXPECT_EQ(f.friction_summary.termination, wb::FitTermination::kConverged);
  EXPECT_TRUE(f.friction_summary.at_bounds.empty());
  EXPECT_GT(f.friction_summary.iterations, 0);
  EXPECT_LE(f.friction_summary.final_cost, f.friction_summary.initial_cost);
  EXPECT_TRUE(f.algorithm1.converged);
  EXPECT_NE(f.poke_source.find("poke"), std::string::npos) << f.poke_source;
  for (const auto& p : Parameters(f, t)) {
    EXPECT_NEAR(p.est.value, p.truth, p.tolerance * p.truth) << p.name;
    EXPECT_GT(p.est.sd, 0) << p.name;
    EXPECT_LT(p.est.lo95, p.est.value) << p.name;
    EXPECT_GT(p.est.hi95, p.est.value) << p.name;
  }
  // The renderer's units follow from the workbench's: K = K1mm / (1 mm)^n.
  EXPECT_NEAR(f.K.value, f.K1mm_N.value / std::pow(1e-3, f.n.value), 1e-9 * f.K.value);
  EXPECT_NEAR(f.B.value, f.B1mm_Ns_per_m.value / std::pow(1e-3, f.n.value), 1e-9 * f.B.value);
  // The friction residual is at the noise (sqrt 2 axes x 8 mN), not the 0.145 N of a 1-D
  // projection of 2-D strokes.
  EXPECT_LT(f.friction_rms_N, 1.5 * std::sqrt(2.0) * 0.008);
}

TEST(ContactFreeHand, AlgorithmOneStartsNearTheTruthFromSlidingAndTremor) {
  const Truth t;
  const auto m = FreeHand(t, 12, 30, 0.006, false);
  const auto r = wb::PrepareReplay(m);
  const auto a = AlgorithmOne(r, wb::Split::kAll);
  EXPECT_TRUE(a.converged);
  EXPECT_GT(a.presliding_samples, 100);
  // The initialiser: eq. 4.10 takes the bristle as saturated above 3 mm/s, which it is not yet
  // in the first tenths of a millimetre of a stroke from rest, so mu_k comes out low by a few
  // per cent (10 % allowed); kappa from the first-order eq. 4.9 on noisy pre-sliding samples
  // only has to be the right magnitude. The joint refinement removes both (test above).
  EXPECT_NEAR(a.mu_k, t.mu_k, 0.10 * t.mu_k);
  EXPECT_GT(a.kappa_N_per_m, t.kappa_N_per_m / 4);
  EXPECT_LT(a.kappa_N_per_m, t.kappa_N_per_m * 4);
}

// Coverage of the reported 95 % intervals over 20 seeds with noise drawn from 4-12 mN: every
// parameter's interval must cover the truth in at least 18 of them (the 90 %), and
// every estimate must be within its tolerance. With the plain (J'J)^-1 sigma^2 of the earlier
// engine, mu_k's interval (+- 0.002) covered the truth in none; with the cluster jackknife alone
// mu_b's covered it in 16 (error mean -1.25 %, SD 1.61 %, median SE 1.08 %): the replay's
// preprocessing (the noisy load through the bristle's saturation, the smoothed positions, the
// decimated rate) leaves a per-recording error that no resampling of the recording sees. The
// friction is now bias-corrected and its SE taken by a parametric bootstrap through that
// preprocessing (wb::BootstrapFriction): K1mm 19, n 20, B1mm 20, kappa 20, mu_k 20, mu_b 19
// (mu_b error mean -0.53 %, SD 1.39 %, median SE 1.38 %); on seeds 200-219, where the choice
// was made: 19, 19, 18, 19, 20, 18. docs/modeling-geometry-contact.md, "Round 4".
TEST(ContactFreeHand, NinetyFivePercentIntervalsCoverTheTruth) {
  const auto c = RunCoverage({});
  EXPECT_EQ(c.usable, 20) << "every fit usable";
  for (const auto& [name, n] : c.covered) {
    EXPECT_GE(n, 18) << name << ": the 95 % interval covered the truth in " << n << " of 20 seeds";
    EXPECT_EQ(c.within.at(name), 20) << name << " outside its tolerance";
  }
}

TEST(ContactOneLine, StrokesAlongALineAndSeparatePokes) {
  // Strokes along x (the renderer's own force model), pokes from a separate file.
  renderer::MaterialModel mat;
  mat.contact.texture = {1000, 0, 1};
  mat.contact.base = {2000, 0, 1};
  mat.contact.layer_thickness_m = 1e-3;
  mat.friction = {3000, 0.35, 0.4};
  renderer::ForceModel model(mat, renderer::ForceAlgorithm::kWall, 2000);
  Rng rng(7);
  Measurement strokes;
  strokes.file = "strokes";
  double x = 0, t = 0;
  for (int cycle = 0; cycle < 8; ++cycle) {
    const double dir = cycle % 2 ? -1.0 : 1.0, fast = 0.02 + 0.01 * (cycle % 6);
    std::vector<double> profile(600, 3e-4);
    for (int i = 0; i < 100; ++i) profile.push_back(3e-4 + fast * i / 100);
    for (int i = 0; i < 500; ++i) profile.push_back(fast);
    for (int i = 0; i < 100; ++i) profile.push_back(fast * (1 - i / 100.0));
    for (double v : profile) {
      x += dir * v * 1e-3;
      t += 1e-3;
      renderer::ToolState s;
      s.p_m = {x, 0, -0.5e-3 - 0.3e-3 * std::sin(2 * std::numbers::pi * 0.7 * t)};
      s.v_mps = {dir * v, 0,
                 0.3e-3 * 2 * std::numbers::pi * 0.7 * std::cos(2 * std::numbers::pi * 0.7 * t)};
      const auto f = model.Step(s);
      MeasurementRow r;
      r.t_s = t;
      r.p_m = s.p_m;
      r.v_mps = s.v_mps;
      r.f_N = f.force_N +
              Eigen::Vector3d(rng.Normal(0, 0.005), rng.Normal(0, 0.005), rng.Normal(0, 0.005));
      strokes.rows.push_back(r);
    }
  }
  Measurement pokes;
  pokes.file = "pokes";
  const double K = 3.0e4, B = 9.0e4, n = 1.3;
  for (int i = 0; i < 3000; ++i) {
    const double tt = i * 1e-3, w = 2 * std::numbers::pi * 4;
    const double d = 0.35e-3 * (1 - std::cos(w * tt)), dd = 0.35e-3 * w * std::sin(w * tt);
    MeasurementRow r;
    r.t_s = tt;
    r.p_m = {0, 0, -d};
    r.v_mps = {0, 0, -dd};
    const double dn = std::pow(std::max(d, 0.0), n);
    r.f_N = {0, 0, std::max(0.0, K * dn + B * dn * dd) + rng.Normal(0, 0.005)};
    pokes.rows.push_back(r);
  }
  const auto f = FitContact(strokes, &pokes);
  EXPECT_TRUE(f.IsUsable());
  // 5 %, mu_b 25 % (the bound: 8 strokes at 20-70 mm/s leave mu_b v at 8-28 mN).
  EXPECT_NEAR(f.kappa_N_per_m.value, 3000, 0.05 * 3000);
  EXPECT_NEAR(f.mu_k.value, 0.35, 0.05 * 0.35);
  EXPECT_NEAR(f.mu_b_Ns_per_m.value, 0.4, 0.25 * 0.4);
  EXPECT_NEAR(f.K.value, K, 0.05 * K);
  EXPECT_NEAR(f.B.value, B, 0.05 * B);
  EXPECT_NEAR(f.n.value, n, 0.05 * n);
  EXPECT_NE(f.poke_source.find("pokes file"), std::string::npos);
  // Samples above 2 N are discarded: the pokes peak near 2.4 N.
  int above = 0;
  for (const auto& r : pokes.rows) above += r.f_N.z() > 2.0;
  EXPECT_GT(above, 0);
  EXPECT_LT(f.poke_samples,
            static_cast<int>(pokes.rows.size() - above) / 2 + 1);  // decimated to 500 Hz
}

TEST(ContactOneLine, RefusesTooLittleDataNamingTheFile) {
  Measurement tiny;
  tiny.file = "tiny.csv";
  for (int i = 0; i < 5; ++i) {
    MeasurementRow r;
    r.t_s = i * 1e-3;
    r.p_m = {0, 0, -1e-4};
    r.f_N = {0, 0, 0.5};
    tiny.rows.push_back(r);
  }
  try {
    FitContact(tiny);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tiny.csv"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::modeling::contact_test
