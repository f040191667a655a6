// anisotropic-friction: the friction coefficient depends on the direction of motion.
#include <numbers>

#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Anisotropic friction: the coefficient depends on the direction of motion "
    "phi, mu(phi) = mu_k (1 + a1 cos phi + b1 sin phi + a2 cos 2phi + b2 sin "
    "2phi). The second harmonic describes grain, grooves or weave (along differs "
    "from across); the first describes a nap or scales that are smoother one way "
    "than the other.";

class AnisotropicFriction final : public BasicEffect {
 public:
  AnisotropicFriction()
      : BasicEffect({.name = effect::kAnisotropicFriction,
                     .modifies_coulomb = true,
                     .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    const char* docs[4] = {"cos phi", "sin phi", "cos 2 phi", "sin 2 phi"};
    std::vector<ParamSpec> p;
    for (int k = 0; k < 4; ++k)
      p.push_back(ModulationCoefficient(std::string(key::kAnisotropy[k].name), docs[k]));
    return p;
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    const double f = 1 + p[0] * std::cos(s.dir_rad) + p[1] * std::sin(s.dir_rad) +
                     p[2] * std::cos(2 * s.dir_rad) + p[3] * std::sin(2 * s.dir_rad);
    t.mu_scale *= std::max(f, 0.05);
  }
  std::vector<ParamSpec> TruthSpecs() const override {
    const char* docs[4] = {"cos phi", "sin phi", "cos 2 phi", "sin 2 phi"};
    const double init[4] = {0, 0, 0.25, 0};
    std::vector<ParamSpec> p;
    for (int k = 0; k < 4; ++k) {
      p.push_back(ModulationCoefficient(std::string(key::kAnisotropy[k].name), docs[k]));
      p.back().init = init[k];
    }
    return p;
  }
  void TruthFriction(const double* p, const TruthSample& s, TruthFrictionTerms& t) const override {
    t.mu_scale *= 1 + p[0] * std::cos(s.dir_rad) + p[1] * std::sin(s.dir_rad) +
                  p[2] * std::cos(2 * s.dir_rad) + p[3] * std::sin(2 * s.dir_rad);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    std::vector<double> edges;
    for (int k = 0; k <= 8; ++k) edges.push_back(-std::numbers::pi + k * std::numbers::pi / 4);
    edges.back() += 1e-9;
    const auto b = SampleBins(
        r, [&](std::size_t i) { return RatioResidual(r, res, i); },
        [&](std::size_t i) { return r.samples()[i].dir_rad; },
        [&](std::size_t i) { return Sliding(r, i); }, edges);
    const int hi = b.ArgMax(), lo = b.ArgMin();
    if (hi < 0) return {"too few sliding samples to judge", "", false};
    const auto deg = [&](int j) { return (b.lo[j] + b.hi[j]) / 2 * 180 / std::numbers::pi; };
    return {fmt::format("friction-ratio residual ranges from {:+.3f} (moving toward {:.0f} deg) to "
                        "{:+.3f} (toward {:.0f} "
                        "deg)",
                        b.mean[lo], deg(lo), b.mean[hi], deg(hi)),
            "friction depends on the direction of motion", !(b.mean[hi] - b.mean[lo] > 0.02)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeAnisotropicFriction() {
  return std::make_unique<AnisotropicFriction>();
}
}  // namespace hapticlab::modeling::wb
