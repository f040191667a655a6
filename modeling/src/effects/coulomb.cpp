// coulomb: kinetic friction proportional to the normal load (Amontons-Coulomb), eq. 4.6's f_C.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Kinetic (Coulomb) friction: while sliding, the surface resists the motion "
    "with a force mu_k f_n opposite to the velocity, independent of speed and "
    "contact area (Amontons' laws). It is the Coulomb level f_C = mu_k f_n that "
    "the Dahl bristle saturates to (dissertation eq. 4.6) and the largest part of "
    "the tangential force on most samples.";

class Coulomb final : public BasicEffect {
 public:
  Coulomb() : BasicEffect({.name = effect::kCoulomb, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay& r) const override {
    // Initial value: median measured friction ratio while sliding.
    std::vector<double> ratio;
    for (const auto& s : r.samples())
      if (s.contact && s.speed_mps >= kSlidingSpeed_mps && s.fn_N > 0.05)
        ratio.push_back(std::hypot(s.ftx_N, s.fty_N) / s.fn_N);
    double init = 0.3;
    if (!ratio.empty()) {
      std::nth_element(ratio.begin(), ratio.begin() + ratio.size() / 2, ratio.end());
      init = std::clamp(ratio[ratio.size() / 2], 0.01, 2.0);
    }
    return {{.name = std::string(key::kMuK.name),
             .unit = "1",
             .init = init,
             .lo = 0,
             .hi = 3,
             .scale = 0.3,
             .doc = "kinetic friction coefficient"}};
  }
  void Friction(const double* p, const Replay::Sample&, FrictionTerms& t) const override {
    t.mu_k = p[0];
  }
  // Truth: the simulator's Coulomb level mu_k (times the other effects' modulations).
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kMuK.name),
             .unit = "1",
             .init = 0.3,
             .lo = 0,
             .hi = 3,
             .doc = "kinetic friction coefficient"}};
  }
  void TruthFriction(const double* p, const TruthSample&, TruthFrictionTerms& t) const override {
    t.mu_k = p[0];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto b = SampleBins(
        r, [&](std::size_t i) { return res.friction_N[i]; },
        [&](std::size_t i) { return r.samples()[i].fn_N; },
        [&](std::size_t i) { return Sliding(r, i); }, {0, 0.5, 1, 1.5, 2, 3, 1e9});
    const int lo = b.First(), hi = b.Last();
    if (lo < 0) return {"too few sliding samples to judge", "", false};
    return {fmt::format("while sliding, the friction residual is {} at loads of {:.1f}-{:.1f} N "
                        "and {} at {:.1f}-{:.1f} N",
                        Mn(b.mean[lo]), b.lo[lo], b.hi[lo], Mn(b.mean[hi]), b.lo[hi],
                        std::min(b.hi[hi], 9.9)),
            "a resistance that grows with the normal load is missing", !(b.mean[hi] > 0.005)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeCoulomb() { return std::make_unique<Coulomb>(); }
}  // namespace hapticlab::modeling::wb
