// vibration-force: the vibration spectrum depends on the normal load (the AR bank's force axis).
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;
constexpr int kKnots = 3;

class VibrationForce final : public Effect {
 public:
  std::string_view name() const override { return "vibration-force"; }
  Channel channel() const override { return Channel::kVibration; }
  std::string_view description() const override {
    return "Load-dependent vibration: pressing harder drives the tool deeper into the "
           "micro-geometry and changes the contact's stiffness, so the vibration level (and "
           "the resonances) change with the normal force (the force axis of the dissertation's "
           "AR bank, ch. III). Modelled as a piecewise-linear function of ln(f_n) per band.";
  }
  std::vector<ParamSpec> Params(const Replay& r) const override {
    const auto k = LogQuantileKnots(r, kKnots, false);
    std::vector<ParamSpec> p;
    for (int i = 0; i < kKnots; ++i) p.push_back({fmt::format("knot{}", i), "ln(N)", k[i], -1e9, 1e9, 1, false, "knot"});
    return p;
  }
  int VibrationColumns() const override { return kKnots - 1; }
  void VibrationFeatures(const double* p, const Replay::Window& w, double* out) const override {
    double h[kKnots];
    Hats(p, kKnots, std::log(std::max(w.force_N, 1e-3)), h);
    for (int i = 1; i < kKnots; ++i) out[i - 1] = h[i];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto use = [](std::size_t) { return true; };
    const double c = Correlation(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return std::log(std::max(r.windows[w].force_N, 1e-3)); }, use);
    const auto b = BinMeans(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return r.windows[w].force_N; }, use, {0, 0.5, 1, 1.5, 2, 3, 1e9});
    const int lo = b.First(5), hi = b.Last(5);
    if (lo < 0 || lo == hi) return {"too narrow a range of loads to judge", "", false};
    return {fmt::format("vibration band-power residual is {:+.1f} dB at {:.1f}-{:.1f} N and {:+.1f} dB at {:.1f}-{:.1f} N "
                        "(correlation with ln f_n {:+.2f})",
                        b.mean[lo], b.lo[lo], b.hi[lo], b.mean[hi], b.lo[hi], std::min(b.hi[hi], 9.9), c),
            "the vibration level changes with the normal force", false};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeVibrationForce() { return std::make_unique<VibrationForce>(); }
}  // namespace hapticlab::modeling::wb
