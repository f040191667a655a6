#include "hapticlab/renderer/energy.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace hapticlab::renderer::energy_test {
namespace {

MaterialModel Elastic() {
  MaterialModel m;
  m.contact.texture = {1000, 0, 1};
  m.contact.base = {2000, 0, 1};
  m.contact.layer_thickness_m = 1e-3;
  m.friction = {2000, 0, 0};
  return m;
}

TEST(Energy, NormOnASineMatchesEquation52) {
  for (const auto& [a, l] : {std::pair{1e-4, 1e-3}, {5e-5, 2e-3}, {2e-4, 1e-3}}) {
    const auto r = ComputeEnergy(Elastic(), ForceAlgorithm::kNorm, a, l, EnergyPath{});
    ASSERT_TRUE(r.has_closed_form);
    EXPECT_GT(r.closed_form_J, 0.0);  // algorithm A creates energy
    EXPECT_NEAR(r.energy_J, r.closed_form_J, 0.01 * r.closed_form_J) << "A=" << a << " l=" << l;
  }
}

TEST(Energy, ClosedFormVanishesForSmallSlopesAsTheFourthPower) {
  // eq. (5.2) ~ K l^2 s^4 / (32 pi^2) with s = 2 pi A / l.
  const double k = 1000, l = 1e-3, a = 1e-6, s = 2 * std::numbers::pi * a / l;
  EXPECT_NEAR(ClosedFormEnergyNorm(k, a, l),
              k * l * l * std::pow(s, 4) / (32 * std::pow(std::numbers::pi, 2)),
              1e-3 * k * l * l * std::pow(s, 4));
}

TEST(Energy, FrictionAlgorithmsGainLittleOnPathB) {
  auto m = Elastic();
  m.friction = {2000, 0.4, 0};
  EnergyPath p;
  p.kind = EnergyPath::Kind::kB;
  p.dx_max_m = 1e-4;
  p.dz_max_m = 1e-4;
  for (auto alg : {ForceAlgorithm::kFric1, ForceAlgorithm::kFric2}) {
    const auto r = ComputeEnergy(m, alg, 1e-4, 1e-3, p);
    ASSERT_TRUE(r.has_closed_form);
    // The normal part is K (T(dx) - T(0)) dz; friction only adds eq. (5.3)'s order or less.
    EXPECT_NEAR(r.normal_energy_J, r.closed_form_J, 0.01 * r.closed_form_J) << ToString(alg);
    EXPECT_LE(r.tangential_energy_J, r.bound_J) << ToString(alg);
    EXPECT_LE(r.energy_J, r.gain_bound_J) << ToString(alg);
  }
  // A flat wall with friction is passive.
  EXPECT_LE(ComputeEnergy(m, ForceAlgorithm::kWall, 1e-4, 1e-3, p).energy_J, 1e-15);
}

}  // namespace
}  // namespace hapticlab::renderer::energy_test
