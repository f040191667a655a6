// load-dependent-friction: the friction coefficient depends on the normal load.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Load-dependent friction: the friction force grows sub- or super-linearly "
    "with load, f_C = mu_k f_n (f_n / 1 N)^(alpha - 1). Elastomers, skin-like and "
    "soft coated materials have alpha < 1 (real contact area grows like f_n^(2/3) "
    "in Hertzian contact), so the friction coefficient falls as the user presses "
    "harder.";

class LoadDependentFriction final : public BasicEffect {
 public:
  LoadDependentFriction()
      : BasicEffect({.name = effect::kLoadDependentFriction,
                     .modifies_coulomb = true,
                     .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay&) const override {
    return {{.name = std::string(key::kLoadAlpha.name),
             .unit = "1",
             .init = 1.0,
             .lo = 0.2,
             .hi = 1.8,
             .scale = 0.1,
             .doc = "load exponent (1: Coulomb)"}};
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    t.mu_scale *= std::pow(std::max(s.fload_N, 0.02), p[0] - 1);
  }
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(key::kLoadAlpha.name),
             .unit = "1",
             .init = 0.7,
             .lo = 0.2,
             .hi = 1.8,
             .doc = "load exponent (1: Coulomb)"}};
  }
  void TruthFriction(const double* p, const TruthSample& s, TruthFrictionTerms& t) const override {
    t.mu_scale *= std::pow(s.fn_N, p[0] - 1);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto b = SampleBins(
        r, [&](std::size_t i) { return res.ratio[i]; },
        [&](std::size_t i) { return r.samples()[i].fn_N; },
        [&](std::size_t i) { return Sliding(r, i); }, {0.05, 0.5, 1, 1.5, 2, 3, 1e9});
    const int lo = b.First(), hi = b.Last();
    if (lo < 0 || lo == hi) return {"too narrow a range of loads to judge", "", false};
    const double d = b.mean[hi] - b.mean[lo];
    return {
        fmt::format(
            "friction-ratio residual is {:+.3f} at {:.1f}-{:.1f} N and {:+.3f} at {:.1f}-{:.1f} N",
            b.mean[lo], b.lo[lo], b.hi[lo], b.mean[hi], b.lo[hi], std::min(b.hi[hi], 9.9)),
        fmt::format("the friction coefficient {} with load", d < 0 ? "falls" : "rises"),
        std::abs(d) < 0.01};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeLoadDependentFriction() {
  return std::make_unique<LoadDependentFriction>();
}
}  // namespace hapticlab::modeling::wb
