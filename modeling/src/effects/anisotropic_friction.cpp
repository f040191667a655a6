// anisotropic-friction: the friction coefficient depends on the direction of motion.
#include <numbers>

#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

class AnisotropicFriction final : public Effect {
 public:
  std::string_view name() const override { return "anisotropic-friction"; }
  Channel channel() const override { return Channel::kFriction; }
  std::vector<std::string_view> requires_effects() const override { return {"coulomb"}; }
  std::string_view description() const override {
    return "Anisotropic friction: the coefficient depends on the direction of motion phi, "
           "mu(phi) = mu_k (1 + a1 cos phi + b1 sin phi + a2 cos 2phi + b2 sin 2phi). The second "
           "harmonic describes grain, grooves or weave (along differs from across); the first "
           "describes a nap or scales that are smoother one way than the other.";
  }
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = "a1",
             .unit = "1",
             .init = 0,
             .lo = -0.9,
             .hi = 0.9,
             .scale = 0.1,
             .fitted = true,
             .doc = "cos phi"},
            {.name = "b1",
             .unit = "1",
             .init = 0,
             .lo = -0.9,
             .hi = 0.9,
             .scale = 0.1,
             .fitted = true,
             .doc = "sin phi"},
            {.name = "a2",
             .unit = "1",
             .init = 0,
             .lo = -0.9,
             .hi = 0.9,
             .scale = 0.1,
             .fitted = true,
             .doc = "cos 2 phi"},
            {.name = "b2",
             .unit = "1",
             .init = 0,
             .lo = -0.9,
             .hi = 0.9,
             .scale = 0.1,
             .fitted = true,
             .doc = "sin 2 phi"}};
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    const double f = 1 + p[0] * std::cos(s.dir_rad) + p[1] * std::sin(s.dir_rad) +
                     p[2] * std::cos(2 * s.dir_rad) + p[3] * std::sin(2 * s.dir_rad);
    t.mu_scale *= std::max(f, 0.05);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    std::vector<double> edges;
    for (int k = 0; k <= 8; ++k) edges.push_back(-std::numbers::pi + k * std::numbers::pi / 4);
    edges.back() += 1e-9;
    const auto b = BinMeans(
        r.samples().size(),
        [&](std::size_t i) {
          return r.samples()[i].fn_N > 0.05 ? res.friction_N[i] / r.samples()[i].fn_N : 0;
        },
        [&](std::size_t i) { return r.samples()[i].dir_rad; },
        [&](std::size_t i) {
          return r.samples()[i].contact && r.samples()[i].speed_mps >= kSlidingSpeed_mps;
        },
        edges);
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
