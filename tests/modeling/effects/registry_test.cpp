// effects/registry.cpp: the catalogue lists every effect source once, with the channel and the
// dependencies its physics implies; an effect registered by a program (here a toy one) is fit,
// scored, diagnosed and simulated like a built-in one, and is gone when its registration ends.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>
#include <string>

#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::registry_test {
namespace {

TEST(EffectRegistry, ListsEverySourceFileOnceInAFixedOrder) {
  // One effect per file of modeling/src/effects/ (vibration_axis.cpp holds both axes).
  std::multiset<std::string> from_files;
  for (const auto& f :
       std::filesystem::directory_iterator(std::string(HL_SOURCE_DIR) + "/modeling/src/effects")) {
    if (f.path().extension() != ".cpp") continue;
    std::string stem = f.path().stem().string();
    if (stem == "registry" || stem == "effect_util") continue;
    if (stem == "vibration_axis") {
      from_files.insert("vibration-speed");
      from_files.insert("vibration-force");
      continue;
    }
    std::replace(stem.begin(), stem.end(), '_', '-');
    from_files.insert(stem);
  }
  std::multiset<std::string> listed;
  for (const auto& e : Catalogue()) listed.insert(std::string(e->name()));
  EXPECT_EQ(listed, from_files);
  EXPECT_EQ(std::set<std::string>(listed.begin(), listed.end()).size(), listed.size())
      << "each effect once";
  // The same objects every call (a static catalogue), lookups by name.
  EXPECT_EQ(&Catalogue(), &Catalogue());
  for (const auto& e : Catalogue()) EXPECT_EQ(FindEffect(e->name()), e.get());
  EXPECT_EQ(FindEffect("core"), nullptr) << "the core is not an entry: every model has it";
  EXPECT_EQ(FindEffect(""), nullptr);
  EXPECT_EQ(std::string(Catalogue().front()->name()), "coulomb");
  EXPECT_EQ(CatalogueNames().find("coulomb, viscous, dahl, stribeck"), 0u);
}

TEST(EffectRegistry, ChannelsAndDependenciesFollowThePhysics) {
  const std::map<std::string, Channel> channel = {
      {"coulomb", Channel::kFriction},
      {"viscous", Channel::kFriction},
      {"dahl", Channel::kFriction},
      {"stribeck", Channel::kFriction},
      {"anisotropic-friction", Channel::kFriction},
      {"load-dependent-friction", Channel::kFriction},
      {"position-dependent-friction", Channel::kFriction},
      {"hc-damping", Channel::kNormal},
      {"hc-exponent", Channel::kNormal},
      {"base-layer", Channel::kNormal},
      {"vibration-speed", Channel::kVibration},
      {"vibration-force", Channel::kVibration},
      {"vibration-direction", Channel::kVibration}};
  // Effects that shape the Coulomb level f_C need the coulomb effect's mu_k.
  const std::set<std::string> modify_coulomb = {"dahl", "stribeck", "anisotropic-friction",
                                                "load-dependent-friction",
                                                "position-dependent-friction"};
  ASSERT_EQ(Catalogue().size(), channel.size());
  for (const auto& e : Catalogue()) {
    const std::string n(e->name());
    ASSERT_TRUE(channel.count(n)) << n;
    EXPECT_EQ(e->channel(), channel.at(n)) << n;
    const auto deps = e->requires_effects();
    if (modify_coulomb.count(n)) {
      ASSERT_EQ(deps.size(), 1u) << n;
      EXPECT_EQ(deps[0], "coulomb") << n;
    } else {
      EXPECT_TRUE(deps.empty()) << n;
    }
    EXPECT_EQ(e->VibrationColumns() > 0, e->channel() == Channel::kVibration) << n;
  }
}

// A toy effect a program could add: ribs across x every 8 mm modulate the friction coefficient,
// mu_k (1 + a sin(2 pi x / 8 mm)). Nothing of the workbench knows it.
constexpr ParamKey kRibs{"toy-ribs", "amplitude"};
double Rib(double x_m) { return std::sin(2 * std::numbers::pi * x_m / 8e-3); }

class ToyRibs final : public Effect {
 public:
  std::string_view name() const override { return kRibs.effect; }
  Channel channel() const override { return Channel::kFriction; }
  std::string_view description() const override { return "ribs across x every 8 mm"; }
  std::vector<std::string_view> requires_effects() const override { return {effect::kCoulomb}; }
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(kRibs.name), .unit = "1", .lo = -0.9, .hi = 0.9, .scale = 0.1}};
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    t.mu_scale *= 1 + p[0] * Rib(s.x_m);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    // Correlation of the friction-ratio residual with the rib profile while sliding.
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t i = 0; i < r.samples().size(); ++i) {
      const auto& s = r.samples()[i];
      if (!s.contact || s.speed_mps < kSlidingSpeed_mps) continue;
      const double x = Rib(s.x_m), y = res.ratio[i];
      sxy += x * y, sxx += x * x, syy += y * y;
    }
    const double c = sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0;
    return {fmt::format("friction-ratio residual follows the ribs (r = {:+.2f})", c),
            "friction is higher on the ribs", !(c > 0.2)};
  }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(kRibs.name), .unit = "1", .init = 0.3, .lo = 0, .hi = 0.9}};
  }
  void TruthFriction(const double* p, const TruthSample& s, TruthFrictionTerms& t) const override {
    t.mu_scale *= 1 + p[0] * std::sin(2 * std::numbers::pi * s.x_m / 8e-3);
  }
};

TEST(EffectRegistry, ARegistrationLastsAsLongAsItsObject) {
  const auto built_in = Catalogue().size();
  {
    const EffectRegistration toy(std::make_unique<ToyRibs>());
    ASSERT_EQ(Catalogue().size(), built_in + 1);
    EXPECT_EQ(FindEffect("toy-ribs"), Catalogue().back().get()) << "after the built-in ones";
    EXPECT_NE(CatalogueNames().find(", toy-ribs"), std::string::npos);
    EXPECT_NO_THROW(RequireKnownEffects({"toy-ribs"}, "model.toml", "effects"));
    EXPECT_THROW(EffectRegistration{std::make_unique<ToyRibs>()}, PreconditionError)
        << "a name is registered once";
    EXPECT_EQ(Catalogue().size(), built_in + 1) << "the refused registration left nothing";
  }
  EXPECT_EQ(Catalogue().size(), built_in);
  EXPECT_EQ(FindEffect("toy-ribs"), nullptr);
  EXPECT_THROW(RequireKnownEffects({"toy-ribs"}, "model.toml", "effects"), InputError);
}

TEST(EffectRegistry, AToyEffectIsSimulatedFitScoredAndDiagnosedLikeABuiltInOne) {
  const EffectRegistration toy(std::make_unique<ToyRibs>());
  TruthParams t;
  t.effects = {"coulomb", "hc-exponent", "toy-ribs"};
  t.duration_s = 30;
  t.seed = 11;
  t.Set(kRibs, 0.3);
  const auto sim = Simulate(t);

  // Simulated: the same strokes without the ribs differ by exactly the rib factor (no Dahl:
  // friction is the smoothed Coulomb level, proportional to mu).
  TruthParams plain = t;
  plain.effects = {"coulomb", "hc-exponent"};
  const auto flat = Simulate(plain);
  int sliding = 0;
  for (std::size_t k = 0; k < sim.m.rows.size(); ++k) {
    if (std::abs(flat.ftx_clean[k]) < 0.05) continue;
    const double x = sim.m.rows[k].p_m.x();
    EXPECT_NEAR(sim.ftx_clean[k] / flat.ftx_clean[k], 1 + 0.3 * Rib(x), 1e-3) << k;
    ++sliding;
  }
  EXPECT_GT(sliding, 1000);

  // The truth as a model carries the truth's amplitude (same-named parameter).
  const auto r = PrepareReplay(sim.m);
  EXPECT_EQ(TruthModel(sim, r).At(kRibs), 0.3);

  // Fit on the training blocks recovers it; held out, the model with it is at the noise floor
  // (the truth replayed through the noisy kinematics), the model without it well above.
  Model without, with;
  AddEffects(&without, {"coulomb", "hc-exponent"}, r);
  AddEffects(&with, {"coulomb", "hc-exponent", "toy-ribs"}, r);
  Fit(&without, r, {.split = Split::kTrain});
  const auto report = Fit(&with, r, {.split = Split::kTrain});
  EXPECT_TRUE(report.IsUsable());
  EXPECT_NEAR(with.At(kRibs), 0.3, 0.03);
  const double e0 = ComputeErrors(r, Predict(without, r), Split::kHeldOut).friction.normalized;
  const double e1 = ComputeErrors(r, Predict(with, r), Split::kHeldOut).friction.normalized;
  const double floor = NoiseFloor(sim, r, Split::kHeldOut).friction.normalized;
  EXPECT_LE(e1, 1.10 * floor) << "held-out friction error " << e1 << ", floor " << floor;
  std::printf("[toy] held-out friction error %.4f without, %.4f with the toy, floor %.4f\n", e0, e1,
              floor);
  EXPECT_GT(e0, 1.2 * floor) << "without the ribs " << e0 << ", floor " << floor;

  // Diagnosed: among every catalogue effect the model lacks, the toy ranks first, supported.
  const auto dx = Diagnose(without, r, {.threads = 2});
  ASSERT_FALSE(dx.candidates.empty());
  EXPECT_EQ(dx.candidates.front().effect, "toy-ribs");
  EXPECT_TRUE(dx.candidates.front().supported);
  EXPECT_NE(dx.candidates.front().evidence.find("follows the ribs"), std::string::npos);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::registry_test
