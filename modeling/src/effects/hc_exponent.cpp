// hc-exponent: nonlinear stiffening of the contact, the exponent n of eq. 4.11.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

std::vector<double> DepthEdges(const Replay& r) {
  double dmax = 0;
  for (const auto& s : r.samples())
    if (s.contact) dmax = std::max(dmax, s.d_m);
  std::vector<double> e;
  for (int k = 0; k <= 6; ++k) e.push_back(dmax * k / 6);
  e.back() += 1e-12;
  return e;
}

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Hunt-Crossley exponent: the contact stiffens with depth, f = K (d / 1 mm)^n "
    "with 1 <= n <= 2 (n = 1.5 for a Hertzian sphere on a half-space; "
    "dissertation eq. 4.11). A linear spring (n = 1) then over-predicts the force "
    "at shallow depth and under-predicts it deep, with a smooth curvature in "
    "between.";

class HcExponent final : public BasicEffect {
 public:
  HcExponent()
      : BasicEffect(
            {.name = effect::kHcExponent, .channel = Channel::kNormal, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kN.name),
             .unit = "1",
             .init = 1.1,
             .lo = 1,
             .hi = 2,
             .scale = 0.1,
             .doc = "exponent"}};
  }
  void Normal(const double* p, const Replay::Sample&, NormalTerms& t) const override { t.n = p[0]; }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kN.name),
             .unit = "1",
             .init = 1.3,
             .lo = 1,
             .hi = 2,
             .doc = "exponent"}};
  }
  void TruthNormal(const double* p, const TruthSample&, NormalTerms& t) const override {
    t.n = p[0];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto b = BinMeans(
        r.samples().size(), [&](std::size_t i) { return res.normal_N[i]; },
        [&](std::size_t i) { return r.samples()[i].d_m; },
        [&](std::size_t i) { return r.samples()[i].contact; }, DepthEdges(r));
    const int lo = b.First(), hi = b.Last();
    if (lo < 0 || hi - lo < 2) return {"too narrow a range of penetration to judge", "", false};
    const int mid = (lo + hi) / 2;
    const bool curved = b.mean[lo] < b.mean[mid] - 0.005 || b.mean[hi] > b.mean[mid] + 0.005;
    return {fmt::format("normal-force residual is {} at {:.2f} mm, {} at {:.2f} mm and {} at "
                        "{:.2f} mm of penetration",
                        Mn(b.mean[lo]), (b.lo[lo] + b.hi[lo]) * 500, Mn(b.mean[mid]),
                        (b.lo[mid] + b.hi[mid]) * 500, Mn(b.mean[hi]), (b.lo[hi] + b.hi[hi]) * 500),
            "the force-penetration curve bends upward, the contact stiffens smoothly with depth",
            !curved};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeHcExponent() { return std::make_unique<HcExponent>(); }
}  // namespace hapticlab::modeling::wb
