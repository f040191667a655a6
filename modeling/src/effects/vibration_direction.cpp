// vibration-direction: the vibration spectrum depends on the direction of motion.
#include <numbers>

#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

class VibrationDirection final : public Effect {
 public:
  std::string_view name() const override { return effect::kVibrationDirection; }
  Channel channel() const override { return Channel::kVibration; }
  std::string_view description() const override {
    return "Direction-dependent vibration: on grooved, woven or grained surfaces stroking across "
           "the structure excites far more vibration than stroking along it. Modelled as first "
           "and second harmonics of the direction of motion (cos phi, sin phi, cos 2phi, "
           "sin 2phi, averaged over the window) added to every band's log power.";
  }
  std::vector<ParamSpec> Params(const Replay&) const override { return {}; }
  int VibrationColumns() const override { return 4; }
  void VibrationFeatures(const double*, const Replay::Window& w, double* out) const override {
    for (int i = 0; i < 4; ++i) out[i] = w.dir[i];
  }
  // Truth: across the grain at 0.3 rad + 90 deg the excitation is strongest.
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(truth_key::kDirectionAmplitude.name),
             .unit = "1",
             .init = 0.8,
             .lo = 0,
             .hi = 5,
             .doc = "power factor exp(amplitude cos 2 (phi - 0.3 rad))"}};
  }
  void TruthVibration(const double* p, const TruthSample& s,
                      TruthVibrationTerms& t) const override {
    t.power *= std::exp(p[0] * std::cos(2 * (s.dir_rad - 0.3)));
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    // Axial direction (0-180 deg) bins: along vs across a structure.
    std::vector<double> e;
    for (int k = 0; k <= 4; ++k) e.push_back(-std::numbers::pi / 2 + k * std::numbers::pi / 4);
    e.back() += 1e-9;
    const auto b = BinMeans(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return 0.5 * std::atan2(r.windows[w].dir[3], r.windows[w].dir[2]); },
        [](std::size_t) { return true; }, e);
    const int hi = b.ArgMax(5), lo = b.ArgMin(5);
    if (hi < 0) return {"too few windows to judge", "", false};
    const auto deg = [&](int j) { return (b.lo[j] + b.hi[j]) / 2 * 180 / std::numbers::pi; };
    return {fmt::format("vibration band-power residual is {:+.1f} dB for strokes along {:.0f} deg "
                        "and {:+.1f} dB along {:.0f} "
                        "deg",
                        b.mean[hi], deg(hi), b.mean[lo], deg(lo)),
            "the vibration depends on the direction of motion", false};
  }
};
}  // namespace
std::unique_ptr<Effect> MakeVibrationDirection() { return std::make_unique<VibrationDirection>(); }
}  // namespace hapticlab::modeling::wb
