#include "hapticlab/renderer/force.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::renderer::force_test {
namespace {

MaterialModel Flat(double mu_k = 0.4, double mu_b = 0.5) {
  MaterialModel m;
  m.contact.texture = {800, 0, 1};
  m.contact.base = {3000, 0, 1};
  m.contact.layer_thickness_m = 1e-3;
  m.friction = {2000, mu_k, mu_b};
  return m;
}

ToolState At(double x, double y, double z, double vx = 0, double vy = 0, double vz = 0) {
  ToolState s;
  s.p_m = {x, y, z};
  s.v_mps = {vx, vy, vz};
  return s;
}

TEST(Force, StaticHuntCrossleyInTheLayerAndTheBase) {
  auto m = Flat(0, 0);
  m.contact.texture = {900, 5, 1.5};
  ForceModel f(m, ForceAlgorithm::kFric2, 0);
  // 0.4 mm into a 1 mm layer, at rest: K d^n.
  auto out = f.Step(At(0, 0, 0.6e-3));
  EXPECT_NEAR(out.force_N.z(), 900 * std::pow(0.4e-3, 1.5), 1e-12);
  EXPECT_NEAR(out.force_N.head<2>().norm(), 0, 1e-15);
  // Moving into the surface adds B d^n d'.
  out = f.Step(At(0, 0, 0.6e-3, 0, 0, -0.02));
  EXPECT_NEAR(out.force_N.z(), 900 * std::pow(0.4e-3, 1.5) + 5 * std::pow(0.4e-3, 1.5) * 0.02,
              1e-12);
  // Below the base: the full layer (d_t = T) plus the linear base.
  out = f.Step(At(0, 0, -0.2e-3));
  EXPECT_NEAR(out.force_N.z(), 900 * std::pow(1e-3, 1.5) + 3000 * 0.2e-3, 1e-12);
  // Out of contact: nothing.
  out = f.Step(At(0, 0, 2e-3));
  EXPECT_FALSE(out.in_contact);
  EXPECT_EQ(out.force_N.norm(), 0.0);
  // Withdrawing fast never makes the surface pull.
  out = f.Step(At(0, 0, 0.9e-3, 0, 0, 10.0));
  EXPECT_GE(out.force_N.z(), 0.0);
}

TEST(Force, BaseStiffnessDefaultsToHalfTheDevices) {
  auto m = Flat(0, 0);
  m.contact.base.K = 0;
  ForceModel f(m, ForceAlgorithm::kWall, 1200);
  const auto out = f.Step(At(0, 0, -1e-3));
  EXPECT_NEAR(out.force_N.z(), 800 * 1e-3 + 1200 * 1e-3, 1e-12);
}

TEST(Force, DahlSteadyStateIsCoulombPlusViscous) {
  const double mu_k = 0.4, mu_b = 0.5, v = 0.05, dt = 1e-3;
  ForceModel f(Flat(mu_k, mu_b), ForceAlgorithm::kWall, 0);
  const double z = 0.5e-3;  // f_n = 800 * 0.5e-3 = 0.4 N
  ForceOutput out;
  for (int k = 0; k < 2000; ++k) out = f.Step(At(v * k * dt, 0, z, v, 0, 0));
  EXPECT_NEAR(out.normal_force_N, 0.4, 1e-12);
  EXPECT_NEAR(out.force_N.x(), -(mu_k * 0.4 + mu_b * v), 1e-9);
  EXPECT_NEAR(out.force_N.y(), 0, 1e-12);
  // Reversing: the friction follows the new direction.
  const double x0 = v * 1999 * dt;
  for (int k = 1; k <= 2000; ++k) out = f.Step(At(x0 - v * k * dt, 0, z, -v, 0, 0));
  EXPECT_NEAR(out.force_N.x(), mu_k * 0.4 + mu_b * v, 1e-9);
}

TEST(Force, PreSlidingStiffnessIsKappa) {
  const double kappa = 2000;
  ForceModel f(Flat(0.4, 0), ForceAlgorithm::kWall, 0);
  f.Step(At(0, 0, 0.5e-3));
  // A 1 µm step from rest: |F_D| = f_C (1 - exp(-kappa dx / f_C)) ≈ kappa dx.
  const auto out = f.Step(At(1e-6, 0, 0.5e-3));
  EXPECT_NEAR(-out.force_N.x() / 1e-6, kappa, kappa * 0.01);
  // And exactly the discrete Dahl law of eq. (4.6) with x0 at rest.
  const double fc = 0.4 * 0.4;
  EXPECT_NEAR(-out.force_N.x(), fc * (1 - std::exp(-kappa * 1e-6 / fc)), 1e-12);
}

TEST(Force, TickByTickDahlComposesToTheClosedFormFromRest) {
  // n ticks of dx from rest equal one jump of n dx (eq. 4.6 with |x - x0|).
  const double fc = 0.4 * 0.4, kappa = 2000;
  ForceModel f(Flat(0.4, 0), ForceAlgorithm::kWall, 0);
  f.Step(At(0, 0, 0.5e-3));
  ForceOutput out;
  for (int k = 1; k <= 50; ++k) out = f.Step(At(k * 2e-6, 0, 0.5e-3));
  EXPECT_NEAR(-out.force_N.x(), fc * (1 - std::exp(-kappa * 100e-6 / fc)), 1e-12);
}

TEST(Force, Fric2RaisesFrictionUphillAndLowersItDownhill) {
  auto m = Flat(0.4, 0);
  m.geometry = std::make_shared<HeightMap>(HeightMap::Sine(5e-6, 1e-3, 5e-6, 1024));
  ForceModel up(m, ForceAlgorithm::kFric2, 0), down(m, ForceAlgorithm::kFric2, 0);
  // At x = 0 the slope is +2 pi A / l: moving +x is uphill.
  const double z = 0.6e-3;
  for (int k = -200; k <= 0; ++k) up.Step(At(k * 1e-6, 0, z, 0.01, 0, 0));
  for (int k = 200; k >= 0; --k) down.Step(At(k * 1e-6, 0, z, -0.01, 0, 0));
  const auto fu = up.Step(At(1e-7, 0, z, 0.01, 0, 0));
  const auto fd = down.Step(At(-1e-7, 0, z, -0.01, 0, 0));
  const double s = 2 * std::numbers::pi * 5e-6 / 1e-3;
  const double sin_t = s / std::sqrt(1 + s * s);
  EXPECT_NEAR(SinThetaT(s, 0, 1, 0), sin_t, 1e-15);
  EXPECT_GT(fu.friction_N, fd.friction_N);
  EXPECT_NEAR(fu.friction_N / fd.friction_N, (1 + sin_t) / (1 - sin_t), 0.02);
}

TEST(Force, NormPointsAlongTheTextureNormal) {
  auto m = Flat(0, 0);
  m.geometry = std::make_shared<HeightMap>(HeightMap::Sine(5e-6, 1e-3, 5e-6, 1024));
  ForceModel f(m, ForceAlgorithm::kNorm, 0);
  const auto out = f.Step(At(0, 0, 0.9e-3));
  const double s = 2 * std::numbers::pi * 5e-6 / 1e-3;
  EXPECT_NEAR(out.force_N.x() / out.force_N.z(), -s, 1e-3 * s);
}

TEST(Force, Fric1ScalesFrictionByOneMinusNormalizedHeight) {
  auto m = Flat(0.4, 0);
  m.geometry = std::make_shared<HeightMap>(HeightMap::Sine(5e-6, 1e-3, 5e-6, 1024));
  ForceModel f1(m, ForceAlgorithm::kFric1, 0), f0(m, ForceAlgorithm::kWall, 0);
  // At the crest (x = l/4) the normalized height is 1: no friction at all.
  ForceOutput a, b;
  for (int k = 0; k <= 250; ++k) {
    a = f1.Step(At(k * 1e-6, 0, 0.9e-3, 0.01, 0, 0));
    b = f0.Step(At(k * 1e-6, 0, 0.9e-3, 0.01, 0, 0));
  }
  EXPECT_NEAR(a.friction_N, 0.0, 1e-4 * b.friction_N);
  EXPECT_GT(b.friction_N, 0.0);
}

TEST(Force, ParsesAlgorithmNames) {
  for (auto a : {ForceAlgorithm::kWall, ForceAlgorithm::kNorm, ForceAlgorithm::kFric1,
                 ForceAlgorithm::kFric2, ForceAlgorithm::kNone})
    EXPECT_EQ(ParseForceAlgorithm(ToString(a)), a);
  EXPECT_THROW(ParseForceAlgorithm("fric3"), InputError);
}

}  // namespace
}  // namespace hapticlab::renderer::force_test
