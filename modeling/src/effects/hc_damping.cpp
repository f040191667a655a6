// hc-damping: Hunt-Crossley damping of the contact, the B d^n d_dot term of eq. 4.11.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Hunt-Crossley damping: the normal force depends on the penetration rate as "
    "well as on the depth, f = (K + B d_dot) (d / 1 mm)^n (dissertation eq. "
    "4.11), so pressing in meets more force than releasing at the same depth and "
    "the loop dissipates energy. Damping scales with depth, so there is no force "
    "jump at first contact.";

class HcDamping final : public BasicEffect {
 public:
  HcDamping()
      : BasicEffect(
            {.name = effect::kHcDamping, .channel = Channel::kNormal, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kB1mm_Ns_per_m.name),
             .unit = "N s/m",
             .init = 0,
             .lo = 0,
             .hi = 1e5,
             .scale = 10,
             .doc = "damping at 1 mm penetration"}};
  }
  void Normal(const double* p, const Replay::Sample&, NormalTerms& t) const override { t.B = p[0]; }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kB1mm_Ns_per_m.name),
             .unit = "N s/m",
             .init = 20,
             .lo = 0,
             .hi = 1e5,
             .doc = "damping at 1 mm penetration"}};
  }
  void TruthNormal(const double* p, const TruthSample&, NormalTerms& t) const override {
    t.B = p[0];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const double c = Correlation(
        r.samples().size(), [&](std::size_t i) { return res.normal_N[i]; },
        [&](std::size_t i) { return r.samples()[i].ddot_mps; },
        [&](std::size_t i) { return r.samples()[i].contact; });
    return {
        fmt::format("normal-force residual correlates with the penetration rate (r = {:+.2f})", c),
        "pressing in meets more force than releasing at the same depth, a rate-dependent (damping) "
        "force is missing",
        !(c > 0.2)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeHcDamping() { return std::make_unique<HcDamping>(); }
}  // namespace hapticlab::modeling::wb
