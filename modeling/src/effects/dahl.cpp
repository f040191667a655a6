// dahl: pre-sliding elasticity of the contact (bristle model), eq. 4.6.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Pre-sliding (Dahl) friction: before gross sliding the asperities deform "
    "elastically, so friction builds up over a small displacement with stiffness "
    "kappa, saturating at the Coulomb level: dF = kappa (dx - |dx| F / f_C) "
    "(dissertation eq. 4.6). Without it friction jumps to its full value at the "
    "first micrometre of motion; with it, reversals and starts show a ramp of "
    "about f_C / kappa.";

class Dahl final : public BasicEffect {
 public:
  Dahl() : BasicEffect({.name = effect::kDahl, .modifies_coulomb = true, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kKappa_N_per_m.name),
             .unit = "N/m",
             .init = 2000,
             .lo = 10,
             .hi = 1e6,
             .scale = 1000,
             .doc = "pre-sliding stiffness"}};
  }
  void Friction(const double* p, const Replay::Sample&, FrictionTerms& t) const override {
    t.kappa = p[0];
  }
  // Truth: the simulator integrates the bristle itself (explicit Euler, 20 substeps).
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kKappa_N_per_m.name),
             .unit = "N/m",
             .init = 3000,
             .lo = 10,
             .hi = 1e6,
             .doc = "pre-sliding stiffness"}};
  }
  void TruthFriction(const double* p, const TruthSample&, TruthFrictionTerms& t) const override {
    t.kappa_N_per_m = p[0];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    // Residual magnitude in pre-sliding / starting samples vs steady sliding.
    double pre = 0, sl = 0;
    int npre = 0, nsl = 0;
    for (std::size_t i = 0; i < r.samples().size(); ++i) {
      if (!r.samples()[i].contact) continue;
      const double e = res.friction_N[i] * res.friction_N[i];
      if (r.samples()[i].speed_mps < kSlidingSpeed_mps)
        pre += e, ++npre;
      else
        sl += e, ++nsl;
    }
    if (npre < 10 || nsl < 10)
      return {"too few pre-sliding or sliding samples to judge", "", false};
    const double a = std::sqrt(pre / npre), b = std::sqrt(sl / nsl);
    return {fmt::format("friction residual RMS is {:.4f} N below 3 mm/s (starts, stops, reversals) "
                        "against {:.4f} N while "
                        "sliding ({:.1f}x)",
                        a, b, a / std::max(b, 1e-12)),
            "the build-up of friction over the first tenths of a millimetre is not modelled",
            !(a > 1.5 * b)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeDahl() { return std::make_unique<Dahl>(); }
}  // namespace hapticlab::modeling::wb
