// viscous: friction growing linearly with sliding speed, eq. 4.7's mu_b term.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Viscous friction: a tangential force mu_b v proportional to the sliding "
    "velocity, from lubricant films, soft coatings or the damping of a compliant "
    "surface layer (the mu_b term of dissertation eq. 4.7). It shows as friction "
    "that keeps rising with speed.";

class Viscous final : public BasicEffect {
 public:
  Viscous() : BasicEffect({.name = effect::kViscous, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kMuB_Ns_per_m.name),
             .unit = "N s/m",
             .init = 0.0,
             .lo = 0,
             .hi = 1000,
             .scale = 1,
             .doc = "viscous coefficient"}};
  }
  void Friction(const double* p, const Replay::Sample&, FrictionTerms& t) const override {
    t.mu_b = p[0];
  }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kMuB_Ns_per_m.name),
             .unit = "N s/m",
             .init = 0.5,
             .lo = 0,
             .hi = 1000,
             .doc = "viscous coefficient"}};
  }
  void TruthFriction(const double* p, const TruthSample&, TruthFrictionTerms& t) const override {
    t.mu_b_Ns_per_m = p[0];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto use = [&](std::size_t i) { return Sliding(r, i); };
    const double c = Correlation(
        r.samples().size(), [&](std::size_t i) { return res.friction_N[i]; },
        [&](std::size_t i) { return r.samples()[i].speed_mps; }, use);
    const auto b = SampleBins(
        r, [&](std::size_t i) { return res.friction_N[i]; },
        [&](std::size_t i) { return r.samples()[i].speed_mps; }, use,
        {0.003, 0.01, 0.03, 0.06, 0.1, 0.15, 1});
    const int lo = b.First(), hi = b.Last();
    if (lo < 0) return {"too few sliding samples to judge", "", false};
    return {fmt::format("friction residual goes from {} at {:.0f}-{:.0f} mm/s to {} at "
                        "{:.0f}-{:.0f} mm/s (correlation "
                        "with speed {:+.2f})",
                        Mn(b.mean[lo]), b.lo[lo] * 1e3, b.hi[lo] * 1e3, Mn(b.mean[hi]),
                        b.lo[hi] * 1e3, std::min(b.hi[hi], 0.2) * 1e3, c),
            "friction rises with sliding speed", !(c > 0)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeViscous() { return std::make_unique<Viscous>(); }
}  // namespace hapticlab::modeling::wb
