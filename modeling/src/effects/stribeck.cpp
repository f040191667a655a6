// stribeck: friction higher at low sliding speed than at high speed.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Stribeck effect: static and low-speed friction exceed kinetic friction, "
    "decaying to the Coulomb level over a characteristic speed v_s: f_C = f_n "
    "(mu_k + dmu_s exp(-(v / v_s)^2)). It comes from boundary lubrication and "
    "junction growth at rest, and is felt as stick at the start of a stroke.";

class Stribeck final : public BasicEffect {
 public:
  Stribeck()
      : BasicEffect({.name = effect::kStribeck, .modifies_coulomb = true, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kStribeckDmu.name),
             .unit = "1",
             .init = 0.05,
             .lo = 0,
             .hi = 3,
             .scale = 0.1,
             .doc = "static minus kinetic coefficient"},
            {.name = std::string(key::kStribeckSpeed_mps.name),
             .unit = "m/s",
             .init = 0.005,
             .lo = 2e-4,
             .hi = 0.1,
             .scale = 0.005,
             .doc = "Stribeck speed"}};
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    const double u = s.speed_mps / p[1];
    t.mu_add += p[0] * std::exp(-u * u);
  }
  // Truth: sim_truth::StribeckFriction's Gaussian rise, mu_k + dmu_s exp(-(v / v_s)^2).
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kStribeckDmu.name),
             .unit = "1",
             .init = 0.25,
             .lo = 0,
             .hi = 3,
             .doc = "static minus kinetic coefficient"},
            {.name = std::string(key::kStribeckSpeed_mps.name),
             .unit = "m/s",
             .init = 0.004,
             .lo = 2e-4,
             .hi = 0.1,
             .doc = "Stribeck speed"}};
  }
  void TruthFriction(const double* p, const TruthSample&, TruthFrictionTerms& t) const override {
    t.dmu_s = p[0];
    t.stribeck_speed_mps = p[1];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto b = SampleBins(
        r, [&](std::size_t i) { return RatioResidual(r, res, i); },
        [&](std::size_t i) { return r.samples()[i].speed_mps; },
        [&](std::size_t i) { return r.samples()[i].contact && r.samples()[i].speed_mps >= 0.5e-3; },
        {0.0005, 0.002, 0.005, 0.01, 0.02, 0.05, 1});
    const int lo = b.First(10), hi = b.Last();
    if (lo < 0 || hi < 0) return {"too few slow sliding samples to judge", "", false};
    const bool pattern = b.mean[lo] > b.mean[hi] + 0.01;
    return {fmt::format("friction-ratio residual is {:+.3f} at {:.1f}-{:.1f} mm/s and {:+.3f} at "
                        "{:.0f}-{:.0f} mm/s{}",
                        b.mean[lo], b.lo[lo] * 1e3, b.hi[lo] * 1e3, b.mean[hi], b.lo[hi] * 1e3,
                        std::min(b.hi[hi], 0.2) * 1e3,
                        pattern ? "" : " (no excess friction at low speed)"),
            "positive at low speed and decaying with speed, static friction exceeds kinetic",
            !pattern};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeStribeck() { return std::make_unique<Stribeck>(); }
}  // namespace hapticlab::modeling::wb
