// vibration-speed: the vibration spectrum depends on the scanning speed (the AR bank's speed axis).
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;
constexpr int kKnots = 5;

class VibrationSpeed final : public Effect {
 public:
  std::string_view name() const override { return "vibration-speed"; }
  Channel channel() const override { return Channel::kVibration; }
  std::string_view description() const override {
    return "Speed-dependent vibration: a surface with spatial period lambda excites the tool at "
           "v / lambda, and faster strokes hit the micro-geometry harder, so both the level and "
           "the shape of the acceleration spectrum change with speed (the speed axis of the "
           "dissertation's AR bank, ch. III). Modelled as a piecewise-linear function of ln(v) "
           "per frequency band, with knots at quantiles of the measured speeds.";
  }
  std::vector<ParamSpec> Params(const Replay& r) const override {
    const auto k = LogQuantileKnots(r, kKnots, true);
    std::vector<ParamSpec> p;
    for (int i = 0; i < kKnots; ++i) p.push_back({fmt::format("knot{}", i), "ln(m/s)", k[i], -1e9, 1e9, 1, false, "knot"});
    return p;
  }
  int VibrationColumns() const override { return kKnots - 1; }
  void VibrationFeatures(const double* p, const Replay::Window& w, double* out) const override {
    double h[kKnots];
    Hats(p, kKnots, std::log(w.speed_mps), h);
    for (int i = 1; i < kKnots; ++i) out[i - 1] = h[i];
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto use = [](std::size_t) { return true; };
    const double c = Correlation(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return std::log(r.windows[w].speed_mps); }, use);
    const auto b = BinMeans(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return r.windows[w].speed_mps; }, use, {0.01, 0.02, 0.04, 0.08, 0.16, 1});
    const int lo = b.First(5), hi = b.Last(5);
    if (lo < 0 || lo == hi) return {"too narrow a range of speeds to judge", "", false};
    return {fmt::format("vibration band-power residual is {:+.1f} dB at {:.0f}-{:.0f} mm/s and {:+.1f} dB at {:.0f}-{:.0f} "
                        "mm/s (correlation with ln v {:+.2f})",
                        b.mean[lo], b.lo[lo] * 1e3, b.hi[lo] * 1e3, b.mean[hi], b.lo[hi] * 1e3,
                        std::min(b.hi[hi], 0.3) * 1e3, c),
            "the vibration spectrum changes with speed", false};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeVibrationSpeed() { return std::make_unique<VibrationSpeed>(); }
}  // namespace hapticlab::modeling::wb
