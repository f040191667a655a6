// Dahl and Hunt-Crossley identification on strokes and pokes generated with known
// parameters (the renderer's own force model) plus sensor noise.

#include "hapticlab/modeling/contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/renderer/force.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

#include <nlohmann/json.hpp>

namespace hapticlab::modeling {
namespace {

constexpr double kNoise_N = 0.005;  // force sensor noise (SD)

// Strokes along x at 1 kHz: creep at 0.3 mm/s through pre-sliding after each reversal, then
// slide at 2-8 cm/s; the load varies between about 0.6 and 1.4 N.
Measurement Strokes(double kappa, double mu_k, double mu_b, std::uint64_t seed) {
  renderer::MaterialModel m;
  m.contact.texture = {1000, 0, 1};
  m.contact.base = {2000, 0, 1};
  m.contact.layer_thickness_m = 1e-3;
  m.friction = {kappa, mu_k, mu_b};
  renderer::ForceModel model(m, renderer::ForceAlgorithm::kWall, 2000);
  Rng rng(seed);
  Measurement out;
  out.file = "strokes";
  double x = 0, t = 0;
  const double dt = 1e-3;
  for (int cycle = 0; cycle < 8; ++cycle) {
    const double dir = cycle % 2 ? -1.0 : 1.0, fast = 0.02 + 0.01 * (cycle % 6);
    std::vector<double> profile;
    for (int i = 0; i < 600; ++i) profile.push_back(3e-4);                 // creep
    for (int i = 0; i < 100; ++i) profile.push_back(3e-4 + fast * i / 100);  // accelerate
    for (int i = 0; i < 500; ++i) profile.push_back(fast);                   // slide
    for (int i = 0; i < 100; ++i) profile.push_back(fast * (1 - i / 100.0)); // stop
    for (double v : profile) {
      x += dir * v * dt;
      t += dt;
      const double z = 0.4e-3 * std::sin(2 * std::numbers::pi * 0.7 * t);  // 0.6-1.4 N
      renderer::ToolState s;
      s.p_m = {x, 0, z};
      s.v_mps = {dir * v, 0, 0};
      const auto f = model.Step(s);
      MeasurementRow r;
      r.t_s = t;
      r.p_m = s.p_m;
      r.v_mps = s.v_mps;
      r.f_N = f.force_N + Eigen::Vector3d(rng.Normal(0, kNoise_N), rng.Normal(0, kNoise_N), rng.Normal(0, kNoise_N));
      out.rows.push_back(r);
    }
  }
  return out;
}

// Pokes at 4 Hz, up to 0.7 mm deep, on f = K d^n + B d^n d'.
Measurement Pokes(double K, double B, double n, std::uint64_t seed) {
  Rng rng(seed);
  Measurement out;
  out.file = "pokes";
  for (int i = 0; i < 3000; ++i) {
    const double t = i * 1e-3, w = 2 * std::numbers::pi * 4;
    const double d = 0.35e-3 * (1 - std::cos(w * t)), dd = 0.35e-3 * w * std::sin(w * t);
    MeasurementRow r;
    r.t_s = t;
    r.p_m = {0, 0, -d};
    r.v_mps = {0, 0, -dd};
    const double dn = std::pow(std::max(d, 0.0), n);
    r.f_N = {0, 0, std::max(0.0, K * dn + B * dn * dd) + rng.Normal(0, kNoise_N)};
    out.rows.push_back(r);
  }
  return out;
}

TEST(Contact, DahlRecoveredWithinFivePercent) {
  for (const auto& [kappa, mu_k, mu_b] : {std::tuple{3000.0, 0.35, 0.4}, {1500.0, 0.6, 0.1}}) {
    const auto fit = FitDahl(Strokes(kappa, mu_k, mu_b, 7));
    SCOPED_TRACE(testing::Message() << "kappa " << kappa);
    EXPECT_TRUE(fit.algorithm1_converged);
    EXPECT_LT(fit.algorithm1_passes, 100);
    EXPECT_NEAR(fit.kappa_N_per_m.value, kappa, 0.05 * kappa);
    EXPECT_NEAR(fit.mu_k.value, mu_k, 0.05 * mu_k);
    EXPECT_NEAR(fit.mu_b_Ns_per_m.value, mu_b, 0.05 * mu_b);
    // The reported uncertainty covers the truth (3 standard errors).
    EXPECT_LE(std::abs(fit.mu_k.value - mu_k), 3 * fit.mu_k.sd + 1e-12);
    EXPECT_LE(std::abs(fit.kappa_N_per_m.value - kappa), 3 * fit.kappa_N_per_m.sd + 1e-9);
    EXPECT_NEAR(fit.rms_residual_N, kNoise_N, 0.3 * kNoise_N);
  }
}

TEST(Contact, HuntCrossleyRecoveredWithinFivePercentAndAbove2NDiscarded) {
  // Peaks near 2.4 N at 0.7 mm; B / K = 3 s/m makes damping 2-3 % of the force at these rates.
  const double K = 3.0e4, B = 9.0e4, n = 1.3;
  const auto pokes = Pokes(K, B, n, 3);
  const auto fit = FitHuntCrossley(pokes);
  EXPECT_NEAR(fit.K.value, K, 0.05 * K);
  EXPECT_NEAR(fit.B.value, B, 0.05 * B);
  EXPECT_NEAR(fit.n.value, n, 0.05 * n);
  EXPECT_LE(std::abs(fit.n.value - n), 3 * fit.n.sd);
  EXPECT_LE(std::abs(fit.K.value - K), 3 * fit.K.sd);
  int above = 0;
  for (const auto& r : pokes.rows) above += r.f_N.z() > 2.0;
  EXPECT_GT(above, 0);  // the pokes do exceed 2 N ...
  EXPECT_LT(fit.samples, static_cast<int>(pokes.rows.size()) - above + 1);  // ... and those are not fitted
}

TEST(Contact, SplitsPokesFromStrokesAndRefusesTooLittleData) {
  auto m = Strokes(3000, 0.35, 0.4, 1);
  const auto p = Pokes(3e4, 9e4, 1.3, 2);
  const std::size_t ns = m.rows.size();
  m.rows.insert(m.rows.end(), p.rows.begin(), p.rows.end());
  Measurement strokes, pokes;
  SplitStrokesAndPokes(m, &strokes, &pokes);
  EXPECT_GE(strokes.rows.size(), ns - 10);
  EXPECT_GE(pokes.rows.size(), p.rows.size() - 100);
  Measurement tiny;
  tiny.file = "tiny.csv";
  tiny.rows.assign(p.rows.begin(), p.rows.begin() + 5);
  EXPECT_THROW(FitHuntCrossley(tiny), InputError);
  EXPECT_THROW(FitDahl(tiny), InputError);
}

TEST(Contact, FitContactCommandWritesAModelPartAndJson) {
  test::TempDir dir;
  auto m = Strokes(3000, 0.35, 0.4, 5);
  const auto p = Pokes(3e4, 9e4, 1.3, 6);
  const double t_end = m.rows.back().t_s;
  for (auto r : p.rows) {
    r.t_s += t_end + 1e-3;
    m.rows.push_back(r);
  }
  WriteMeasurementCsv(dir.File("m.csv"), m);
  std::string out;
  ASSERT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model fit-contact --measurement " + dir.File("m.csv") + " -o " +
                                 dir.File("c.toml") + " --json", &out), 0) << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_NEAR(j["dahl"]["mu_k"].get<double>(), 0.35, 0.05 * 0.35);
  EXPECT_NEAR(j["dahl"]["kappa"].get<double>(), 3000, 0.05 * 3000);
  EXPECT_NEAR(j["hunt_crossley"]["n"].get<double>(), 1.3, 0.05 * 1.3);
  EXPECT_GT(j["uncertainty"]["K"]["sd"].get<double>(), 0.0);
  // The written tables make a loadable material model.
  test::WriteFile(dir.File("model.toml"), "name = \"fitted\"\n" + test::ReadFile(dir.File("c.toml")));
  const auto model = renderer::LoadMaterial(dir.File("model.toml"));
  EXPECT_NEAR(model.friction.mu_k, 0.35, 0.05 * 0.35);
}

}  // namespace
}  // namespace hapticlab::modeling
