// base-layer: a stiffer base under a thin compliant layer (eq. 4.15's base).
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t k =
      std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Stiff base under a thin layer: once the tool has pressed through a compliant "
    "layer of thickness t it meets a stiffer base, f += K_b max(0, d - t) (the "
    "base of dissertation eqs. 4.14-4.15; paper on wood, fabric on foam on a "
    "plate, a coating on metal). The force-penetration curve has a knee at d = t "
    "rather than a smooth curvature.";

class BaseLayer final : public BasicEffect {
 public:
  BaseLayer()
      : BasicEffect(
            {.name = effect::kBaseLayer, .channel = Channel::kNormal, .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay& r) const override {
    std::vector<double> d;
    for (const auto& s : r.samples())
      if (s.contact) d.push_back(s.d_m);
    return {{.name = std::string(key::kBaseK_N_per_m.name),
             .unit = "N/m",
             .init = 500,
             .lo = 0,
             .hi = 1e6,
             .scale = 1000,
             .doc = "base stiffness"},
            {.name = std::string(key::kLayer_m.name),
             .unit = "m",
             .init = Quantile(d, 0.6),
             .lo = 0,
             .hi = 0.01,
             .scale = 1e-3,
             .doc = "layer thickness"}};
  }
  void Normal(const double* p, const Replay::Sample& s, NormalTerms& t) const override {
    t.extra_N += p[0] * std::max(0.0, s.d_m - p[1]);
  }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kBaseK_N_per_m.name),
             .unit = "N/m",
             .init = 6000,
             .lo = 0,
             .hi = 1e6,
             .doc = "base stiffness"},
            {.name = std::string(key::kLayer_m.name),
             .unit = "m",
             .init = 0.6e-3,
             .lo = 0,
             .hi = 0.01,
             .doc = "layer thickness"}};
  }
  void TruthNormal(const double* p, const TruthSample& s, NormalTerms& t) const override {
    if (s.d_m > p[1]) t.extra_N += p[0] * (s.d_m - p[1]);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    double dmax = 0;
    for (const auto& s : r.samples())
      if (s.contact) dmax = std::max(dmax, s.d_m);
    std::vector<double> e;
    for (int k = 0; k <= 8; ++k) e.push_back(dmax * k / 8);
    e.back() += 1e-12;
    const auto b = BinMeans(
        r.samples().size(), [&](std::size_t i) { return res.normal_N[i]; },
        [&](std::size_t i) { return r.samples()[i].d_m; },
        [&](std::size_t i) { return r.samples()[i].contact; }, e);
    const int hi = b.Last();
    if (hi < 2) return {"too narrow a range of penetration to judge", "", false};
    // The deepest bin's excess over the trend of the shallower half.
    const int mid = hi / 2;
    return {
        fmt::format("normal-force residual is {} around {:.2f} mm and {} at the deepest {:.2f} mm",
                    Mn(b.mean[mid]), (b.lo[mid] + b.hi[mid]) * 500, Mn(b.mean[hi]),
                    (b.lo[hi] + b.hi[hi]) * 500),
        "the contact gets stiffer beyond some depth, a base under the layer is felt",
        !(b.mean[hi] > b.mean[mid] + 0.01)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeBaseLayer() { return std::make_unique<BaseLayer>(); }
}  // namespace hapticlab::modeling::wb
