// vibration-speed and vibration-force: the vibration spectrum depends on the scanning speed or
// on the normal load (the two axes of the dissertation's AR bank, ch. III). One implementation,
// a piecewise-linear function of ln(key) per frequency band with knots at quantiles of the
// measured key; the two effects differ only in their Axis.
#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;
constexpr int kMaxKnots = 8;

// One axis of the bank: the window's key [m/s or N], and how the evidence reports it.
struct Axis {
  std::string_view name, description;
  int knots;
  bool speed;                 // key: the window's mean speed [m/s]; else its mean load [N]
  const char* knot_unit;      // unit of a knot (ln of the key's unit)
  std::vector<double> edges;  // evidence bins of the key [m/s or N]
  double display_scale;       // key -> displayed unit
  int display_digits;
  double display_cap;  // the last bin's upper edge shown at most this [key units]
  const char* display_unit;
  const char* range_word;  // "speeds", "loads"
  const char* ln_symbol;   // "v", "f_n"
  const char* cause;
  // The simulator's truth: its parameters and how they shape the excitation.
  std::vector<ParamSpec> truth;
  void (*truth_hook)(const double* p, const TruthSample& s, TruthVibrationTerms& t) = nullptr;
  double Key(const Replay::Window& w) const { return speed ? w.speed_mps : w.force_N; }
  double LnKey(const Replay::Window& w) const {
    return speed ? std::log(w.speed_mps) : std::log(std::max(w.force_N, 1e-3));
  }
  std::string Range(double lo, double hi) const {
    return fmt::format("{:.{}f}-{:.{}f} {}", lo * display_scale, display_digits, hi * display_scale,
                       display_digits, display_unit);
  }
};

class VibrationAxis final : public Effect {
 public:
  explicit VibrationAxis(Axis a) : a_(std::move(a)) {}
  std::string_view name() const override { return a_.name; }
  Channel channel() const override { return Channel::kVibration; }
  std::string_view description() const override { return a_.description; }
  std::vector<ParamSpec> Params(const Replay& r) const override {
    const auto k = LogQuantileKnots(r, a_.knots, a_.speed);
    std::vector<ParamSpec> p;
    for (int i = 0; i < a_.knots; ++i)
      p.push_back({.name = fmt::format("{}{}", kKnotPrefix, i),
                   .unit = a_.knot_unit,
                   .init = k[static_cast<std::size_t>(i)],
                   .lo = -1e9,
                   .hi = 1e9,
                   .scale = 1,
                   .fitted = false,
                   .doc = "knot"});
    return p;
  }
  int VibrationColumns() const override { return a_.knots - 1; }
  void VibrationFeatures(const double* p, const Replay::Window& w, double* out) const override {
    double h[kMaxKnots];
    Hats(p, a_.knots, a_.LnKey(w), h);
    for (int i = 1; i < a_.knots; ++i) out[i - 1] = h[i];
  }
  std::vector<ParamSpec> TruthSpecs() const override { return a_.truth; }
  void TruthVibration(const double* p, const TruthSample& s,
                      TruthVibrationTerms& t) const override {
    a_.truth_hook(p, s, t);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    const auto use = [](std::size_t) { return true; };
    const double c = Correlation(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return a_.LnKey(r.windows[w]); }, use);
    const auto b = BinMeans(
        r.windows.size(), [&](std::size_t w) { return MeanBandResidualDb(res, w); },
        [&](std::size_t w) { return a_.Key(r.windows[w]); }, use, a_.edges);
    const int lo = b.First(5), hi = b.Last(5);
    if (lo < 0 || lo == hi)
      return {fmt::format("too narrow a range of {} to judge", a_.range_word), "", false};
    return {fmt::format("vibration band-power residual is {:+.1f} dB at {} and {:+.1f} dB at {} "
                        "(correlation with ln {} "
                        "{:+.2f})",
                        b.mean[lo], a_.Range(b.lo[lo], b.hi[lo]), b.mean[hi],
                        a_.Range(b.lo[hi], std::min(b.hi[hi], a_.display_cap)), a_.ln_symbol, c),
            a_.cause, false};
  }

 private:
  Axis a_;
};
}  // namespace

std::unique_ptr<Effect> MakeVibrationSpeed() {
  return std::make_unique<VibrationAxis>(Axis{
      .name = effect::kVibrationSpeed,
      .description =
          "Speed-dependent vibration: a surface with spatial period lambda excites the tool at "
          "v / lambda, and faster strokes hit the micro-geometry harder, so both the level and "
          "the shape of the acceleration spectrum change with speed (the speed axis of the "
          "dissertation's AR bank, ch. III). Modelled as a piecewise-linear function of ln(v) "
          "per frequency band, with knots at quantiles of the measured speeds.",
      .knots = 5,
      .speed = true,
      .knot_unit = "ln(m/s)",
      .edges = {0.01, 0.02, 0.04, 0.08, 0.16, 1},
      .display_scale = 1e3,
      .display_digits = 0,
      .display_cap = 0.3,
      .display_unit = "mm/s",
      .range_word = "speeds",
      .ln_symbol = "v",
      .cause = "the vibration spectrum changes with speed",
      .truth = {{.name = std::string(truth_key::kSpeedExponent.name),
                 .unit = "1",
                 .init = 1.0,
                 .lo = 0,
                 .hi = 3,
                 .doc = "power grows as (v / 50 mm/s)^(2 exponent)"},
                {.name = std::string(truth_key::kWavelength_m.name),
                 .unit = "m",
                 .init = 0.4e-3,
                 .lo = 1e-5,
                 .hi = 0.01,
                 .doc = "spatial period of the micro-geometry: resonance at v / wavelength"}},
      .truth_hook = [](const double* p, const TruthSample& s, TruthVibrationTerms& t) {
        t.resonance_hz = std::clamp(s.speed_mps / p[1], 30.0, 0.4 * s.rate_hz);
        t.power *= std::pow(s.speed_mps / 0.05, 2 * p[0]);
      }});
}

std::unique_ptr<Effect> MakeVibrationForce() {
  return std::make_unique<VibrationAxis>(
      Axis{.name = effect::kVibrationForce,
           .description =
               "Load-dependent vibration: pressing harder drives the tool deeper into the "
               "micro-geometry and changes the contact's stiffness, so the vibration level (and "
               "the resonances) change with the normal force (the force axis of the dissertation's "
               "AR bank, ch. III). Modelled as a piecewise-linear function of ln(f_n) per band.",
           .knots = 3,
           .speed = false,
           .knot_unit = "ln(N)",
           .edges = {0, 0.5, 1, 1.5, 2, 3, 1e9},
           .display_scale = 1,
           .display_digits = 1,
           .display_cap = 9.9,
           .display_unit = "N",
           .range_word = "loads",
           .ln_symbol = "f_n",
           .cause = "the vibration level changes with the normal force",
           .truth = {{.name = std::string(truth_key::kForceExponent.name),
                      .unit = "1",
                      .init = 0.8,
                      .lo = 0,
                      .hi = 3,
                      .doc = "power grows as (f_n / 1 N)^(2 exponent)"}},
           .truth_hook = [](const double* p, const TruthSample& s, TruthVibrationTerms& t) {
             t.power *= std::pow(s.fn_N, 2 * p[0]);
           }});
}

}  // namespace hapticlab::modeling::wb
