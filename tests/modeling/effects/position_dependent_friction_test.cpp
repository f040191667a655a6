// effects/position_dependent_friction.cpp: a friction coefficient that varies over the surface,
// mu(x, y) = mu_k (1 + sum g_jk P_j(u) P_k(v)) with Legendre polynomials P_0 = 1, P_1 = u,
// P_2 = (3u^2 - 1) / 2 of the position scaled to [-1, 1] over the stroked area.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::position_dependent_friction_test {
namespace {
using namespace effect_test;

double P(int j, double u) { return j == 0 ? 1 : j == 1 ? u : (3 * u * u - 1) / 2; }

// The field over a box [x0, x1] x [y0, y1], coefficients by name "g<j><k>".
double Field(const std::map<std::string, double>& g, double x0, double x1, double y0, double y1,
             double x, double y) {
  const double u = std::clamp(2 * (x - x0) / (x1 - x0) - 1, -1.0, 1.0);
  const double v = std::clamp(2 * (y - y0) / (y1 - y0) - 1, -1.0, 1.0);
  double f = 1;
  for (const auto& [name, c] : g) f += c * P(name[1] - '0', u) * P(name[2] - '0', v);
  return f;
}

// Raster strokes along x and along y over a 20 x 20 mm area centred on the origin.
std::vector<Stroke> Raster() {
  std::vector<Stroke> out;
  for (int k = 0; k <= 8; ++k) {
    const double c = -0.01 + k * 0.0025;
    out.push_back({0, 0.05, 0.05, 1.0, 2.0, 0.4, -0.01, c});
    out.push_back({3.141592653589793 / 2, 0.05, 0.05, 2.0, 1.0, 0.4, c, -0.01});
  }
  return out;
}

void SetField(Model* m, const std::map<std::string, double>& g, const Replay& r) {
  AddEffects(m, {"position-dependent-friction"}, r);
  for (const auto& [name, c] : g)
    m->params[std::string(effect::kPositionDependentFriction)][name] = c;
}

TEST(PositionDependentFrictionEffect, FieldIsTheLegendreSeriesOverTheStrokedBox) {
  const auto r = MakeStrokes(Raster(), [](const Replay::Sample&) { return 0.0; });
  const auto spec = FindEffect(effect::kPositionDependentFriction)->Params(r);
  ASSERT_EQ(spec.size(), 12u);
  // The box is fixed from the data, the eight coefficients start at 0.
  EXPECT_EQ(spec[0].init, r.x_min);
  EXPECT_EQ(spec[1].init, r.x_max);
  EXPECT_EQ(spec[2].init, r.y_min);
  EXPECT_EQ(spec[3].init, r.y_max);
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(spec[k].fitted);
  const char* names[8] = {"g01", "g02", "g10", "g11", "g12", "g20", "g21", "g22"};
  for (int k = 0; k < 8; ++k) {
    EXPECT_EQ(spec[4 + k].name, names[k]);
    EXPECT_TRUE(spec[4 + k].fitted);
    EXPECT_EQ(spec[4 + k].init, 0);
  }
  const std::map<std::string, double> g = {
      {"g10", 0.2}, {"g02", 0.15}, {"g11", -0.1}, {"g22", 0.05}};
  Model m;
  m.effects = {std::string(effect::kCoulomb)};
  m.Set(key::kMuK, 0.3);
  SetField(&m, g, r);
  // Probe points inside the box, on its edges and outside it (clamped to the edge).
  Replay probe;
  for (const double x : {-0.02, -0.01, -0.003, 0.0, 0.006, 0.02})
    for (const double y : {-0.01, 0.004, 0.015}) {
      Replay::Sample s{};
      s.x_m = x, s.y_m = y;
      s.vx_mps = s.speed_mps = 0.05;
      s.fn_N = s.fload_N = 1;
      s.contact = true;
      probe.mutable_samples().push_back(s);
    }
  const auto p = Predict(m, probe);
  for (std::size_t i = 0; i < probe.samples().size(); ++i) {
    const auto& s = probe.samples()[i];
    EXPECT_NEAR(-p.ftx_N[i], 0.3 * Field(g, r.x_min, r.x_max, r.y_min, r.y_max, s.x_m, s.y_m), 1e-9)
        << s.x_m << ", " << s.y_m;
  }
}

TEST(PositionDependentFrictionEffect, FitRecoversTheFieldFromARaster) {
  const auto kin = MakeStrokes(Raster(), [](const Replay::Sample&) { return 0.0; });
  const std::map<std::string, double> g = {{"g10", 0.2}, {"g02", 0.15}, {"g11", -0.1}};
  const auto r = MakeStrokes(
      Raster(),
      [&](const Replay::Sample& s) {
        return 0.35 * s.fload_N *
               Field(g, kin.x_min, kin.x_max, kin.y_min, kin.y_max, s.x_m, s.y_m);
      },
      0, 0.01, 51);
  Model m = ModelOf({"position-dependent-friction"}, r);
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kMuK), 0.35, 0.005);
  for (const char* name : {"g01", "g02", "g10", "g11", "g12", "g20", "g21", "g22"}) {
    const double truth = g.count(name) ? g.at(name) : 0.0;
    EXPECT_NEAR(m.params.at(std::string(effect::kPositionDependentFriction)).at(name), truth, 0.015)
        << name;
  }
}

TEST(PositionDependentFrictionEffect, EvidenceNamesTheTilesAndIsAbsentOnAUniformSurface) {
  const auto kin = MakeStrokes(Raster(), [](const Replay::Sample&) { return 0.0; });
  Model uniform;
  uniform.effects = {std::string(effect::kCoulomb)};
  uniform.Set(key::kMuK, 0.35);
  // Friction 30 % higher towards +x than towards -x.
  const auto r = MakeStrokes(
      Raster(),
      [&](const Replay::Sample& s) {
        return 0.35 * s.fload_N *
               Field({{"g10", 0.15}}, kin.x_min, kin.x_max, kin.y_min, kin.y_max, s.x_m, s.y_m);
      },
      0, 0.01, 52);
  const auto seen = EvidenceOf(effect::kPositionDependentFriction, uniform, r);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  EXPECT_NE(seen.pattern.find("right tile"), std::string::npos) << seen.pattern;
  EXPECT_NE(seen.pattern.find("left tile"), std::string::npos) << seen.pattern;
  const auto flat = MakeStrokes(
      Raster(), [](const Replay::Sample& s) { return 0.35 * s.fload_N; }, 0, 0.01, 53);
  const auto null = EvidenceOf(effect::kPositionDependentFriction, uniform, flat);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::position_dependent_friction_test
