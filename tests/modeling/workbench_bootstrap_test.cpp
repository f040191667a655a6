// The friction channel's parametric bootstrap (modeling/src/workbench_bootstrap.cpp). Its
// coverage over 20 free-hand recordings is tests/modeling/contact_test.cpp's
// `ContactFreeHand.NinetyFivePercentIntervalsCoverTheTruth`; here its parts: the noise it
// measures, and what it reports and writes.

#include "hapticlab/modeling/workbench_bootstrap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "contact_freehand.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::workbench_bootstrap_test {
namespace {

// Smooth motion unlike the free-hand generator's: circles at 20 mm/s with a 2 s rest every
// 6 s, a load of 1 N with a 0.5 Hz wobble, smooth tangential forces; white noise of known SD on
// every channel (std::normal_distribution, not the project's Rng).
Measurement Circles(double sp_m, double sv_mps, double st_N, double sl_N) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0, 1);
  Measurement m;
  m.file = "circles.csv";
  const double fs = 1000, r_m = 0.01, w = 2.0;  // 10 mm radius, 2 rad/s: 20 mm/s
  double phase = 0;
  for (int k = 0; k < 30000; ++k) {
    const double t = k / fs;
    const bool moving = std::fmod(t, 6.0) < 4.0;
    if (moving) phase += w / fs;
    MeasurementRow row;
    row.t_s = t;
    const double vx = moving ? -r_m * w * std::sin(phase) : 0,
                 vy = moving ? r_m * w * std::cos(phase) : 0;
    row.p_m = {r_m * std::cos(phase) + sp_m * g(rng), r_m * std::sin(phase) + sp_m * g(rng), -1e-4};
    row.v_mps = {vx + sv_mps * g(rng), vy + sv_mps * g(rng), 0};
    const double load = 1 + 0.3 * std::sin(2 * std::numbers::pi * 0.5 * t);
    row.f_N = {-0.4 * load * std::sin(phase + 1) + st_N * g(rng),
               0.4 * load * std::cos(phase + 1) + st_N * g(rng), load + sl_N * g(rng)};
    m.rows.push_back(row);
  }
  return m;
}

TEST(WorkbenchBootstrap, NoiseEstimatesRecoverTheNoiseAddedToSmoothSignals) {
  const double sp = 2e-7, sv = 3e-4, st = 0.005, sl = 0.009;
  const auto n = wb::EstimateNoise(Circles(sp, sv, st, sl), 0.02);
  // 12 000 rest rows for the positions, 30 000 rows for the rest: the median's standard error
  // is about 1 %; 5 % allows for the signals' own second differences.
  EXPECT_NEAR(n.position_m, sp, 0.05 * sp);
  EXPECT_NEAR(n.velocity_mps, sv, 0.05 * sv);
  EXPECT_NEAR(n.tangential_N, st, 0.05 * st);
  EXPECT_NEAR(n.load_N, sl, 0.05 * sl);
  // Without noise nothing is invented (the signals' own second differences at 1 kHz are far
  // below any of these noise levels).
  const auto z = wb::EstimateNoise(Circles(0, 0, 0, 0), 0.02);
  EXPECT_LT(z.position_m, 0.05 * sp);
  EXPECT_LT(z.load_N, 0.05 * sl);
}

TEST(WorkbenchBootstrap, CorrectsTheFitItReportsReproducibly) {
  const Truth t;
  const auto m = FreeHand(t, 31, 12, 0.008, false);
  auto run = [&](wb::Model* model, wb::ChannelFit* friction) {
    const auto r = wb::PrepareReplay(m);
    wb::AddEffects(model, {"coulomb", "viscous", "dahl"}, r);
    wb::FitOptions fo;
    fo.normal = fo.vibration = false;
    fo.uncertainty = true;
    auto rep = wb::Fit(model, r, fo);
    *friction = *rep.Find(wb::Channel::kFriction);
    const auto before = *friction;
    wb::BootstrapOptions bo;
    bo.replicates = 6;
    const auto b = wb::BootstrapFriction(model, m, {}, fo, friction, bo);
    EXPECT_TRUE(b.applied) << b.why_not;
    EXPECT_EQ(b.replicates, 6);
    EXPECT_NEAR(b.noise.load_N, 0.008, 0.0008);
    EXPECT_EQ(b.params.size(), before.params.size());
    for (std::size_t k = 0; k < b.params.size(); ++k) {
      const auto& p = b.params[k];
      EXPECT_EQ(p.fit, before.params[k].value);
      EXPECT_DOUBLE_EQ(p.corrected, p.fit - p.bias) << p.name;
      EXPECT_GE(p.sd, p.jackknife_sd) << p.name;
      EXPECT_GE(p.sd, p.bootstrap_sd) << p.name;
      EXPECT_EQ(friction->params[k].value, p.corrected) << p.name;
      EXPECT_LT(friction->params[k].lo95, p.corrected);
      EXPECT_GT(friction->params[k].hi95, p.corrected);
      EXPECT_EQ(model->params.at(p.effect).at(p.name), p.corrected) << p.name;
      // The correction is small against the value: it corrects a preprocessing bias of a few
      // per cent at most, not the fit.
      EXPECT_LT(std::abs(p.bias), 0.05 * std::abs(p.fit)) << p.name;
    }
    return b;
  };
  wb::Model m1, m2;
  wb::ChannelFit f1, f2;
  const auto b1 = run(&m1, &f1), b2 = run(&m2, &f2);
  for (std::size_t k = 0; k < b1.params.size(); ++k)
    EXPECT_EQ(b1.params[k].corrected, b2.params[k].corrected) << "seeded: reproducible";
}

TEST(WorkbenchBootstrap, NotAppliedWithoutMeasurableNoise) {
  const Truth t;
  auto m = FreeHand(t, 32, 12, 0.008, false);
  m.rows.resize(150);  // fewer than 200 rows in contact: no noise estimate
  const auto r = wb::PrepareReplay(m);
  wb::Model model;
  wb::AddEffects(&model, {"coulomb"}, r);
  wb::ChannelFit cf;
  cf.channel = wb::Channel::kFriction;
  cf.params.push_back({"coulomb", "mu_k", 0.45, 0.01, 0.43, 0.47, false});
  const auto b = wb::BootstrapFriction(&model, m, {}, {}, &cf);
  EXPECT_FALSE(b.applied);
  EXPECT_NE(b.why_not.find("noise"), std::string::npos) << b.why_not;
  EXPECT_EQ(cf.params[0].value, 0.45);  // untouched
}

}  // namespace
}  // namespace hapticlab::modeling::workbench_bootstrap_test
