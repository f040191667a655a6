// position-dependent-friction: the friction coefficient varies over the surface.
#include <numbers>

#include "effect_util.hpp"

namespace hapticlab::modeling::wb {
namespace {
using namespace detail;

// Smooth field over the bounding box of the stroked area: 1 + sum g_jk P_j(u) P_k(v) with
// Legendre polynomials P_0..P_2 of the coordinates scaled to [-1, 1], (j, k) != (0, 0): eight
// coefficients. Polynomials keep their form under a change of the box, so a field fitted on
// one measurement means the same on another of the same sample.
constexpr int kOrder = 2;

// What the effect is, for `hapticlab effects` and the reports.
constexpr std::string_view kAbout =
    "Position-dependent friction: the friction coefficient varies over the sample "
    "(worn or polished areas, contamination, a grain that changes across a "
    "board), mu(x, y) = mu_k (1 + sum g_jk P_j(u) P_k(v)) with u, v the position "
    "scaled to [-1, 1] over the measured area and P_j Legendre polynomials of "
    "degree j <= 2. Residuals then differ between tiles of the surface rather "
    "than with speed, load or direction.";

class PositionDependentFriction final : public BasicEffect {
 public:
  PositionDependentFriction()
      : BasicEffect({.name = effect::kPositionDependentFriction,
                     .modifies_coulomb = true,
                     .description = kAbout}) {}
  std::vector<ParamSpec> Params(const Replay& r) const override {
    // The box is fixed from the data: the area the strokes covered [m].
    const std::pair<ParamKey, double> box[4] = {{key::kTileX0_m, r.x_min},
                                                {key::kTileX1_m, r.x_max},
                                                {key::kTileY0_m, r.y_min},
                                                {key::kTileY1_m, r.y_max}};
    std::vector<ParamSpec> p;
    for (const auto& [k, v] : box)
      p.push_back({.name = std::string(k.name),
                   .unit = "m",
                   .init = v,
                   .lo = -1e9,
                   .hi = 1e9,
                   .fitted = false,
                   .doc = "area"});
    for (int j = 0; j <= kOrder; ++j)
      for (int k = 0; k <= kOrder; ++k)
        if (j || k)
          p.push_back(ModulationCoefficient(fmt::format("{}{}{}", kLegendrePrefix, j, k),
                                            "Legendre coefficient"));
    return p;
  }
  void Friction(const double* p, const Replay::Sample& s, FrictionTerms& t) const override {
    const double u = std::clamp(2 * (s.x_m - p[0]) / std::max(p[1] - p[0], 1e-9) - 1, -1.0, 1.0);
    const double v = std::clamp(2 * (s.y_m - p[2]) / std::max(p[3] - p[2], 1e-9) - 1, -1.0, 1.0);
    const double cu[3] = {1, u, 1.5 * u * u - 0.5};
    const double cv[3] = {1, v, 1.5 * v * v - 0.5};
    double f = 1;
    int i = 4;
    for (int j = 0; j <= kOrder; ++j)
      for (int k = 0; k <= kOrder; ++k)
        if (j || k) f += p[i++] * cu[j] * cv[k];
    t.mu_scale *= std::max(f, 0.05);
  }
  EvidenceNote Evidence(const Replay& r, const Residuals& res) const override {
    // Friction-ratio residual per tile of a 3 x 3 grid.
    double m[9] = {}, n[9] = {};
    for (std::size_t i = 0; i < r.samples().size(); ++i) {
      const auto& s = r.samples()[i];
      if (!Sliding(r, i) || s.fn_N < 0.05) continue;
      const int tx = std::clamp(
          static_cast<int>(3 * (s.x_m - r.x_min) / std::max(r.x_max - r.x_min, 1e-9)), 0, 2);
      const int ty = std::clamp(
          static_cast<int>(3 * (s.y_m - r.y_min) / std::max(r.y_max - r.y_min, 1e-9)), 0, 2);
      m[3 * ty + tx] += res.friction_N[i] / s.fn_N;
      n[3 * ty + tx] += 1;
    }
    int lo = -1, hi = -1;
    for (int k = 0; k < 9; ++k) {
      if (n[k] < 20) continue;
      m[k] /= n[k];
      if (lo < 0 || m[k] < m[lo]) lo = k;
      if (hi < 0 || m[k] > m[hi]) hi = k;
    }
    if (lo < 0) return {"too few sliding samples to judge", "", false};
    static constexpr const char* kTile[9] = {"front-left",  "front-centre", "front-right",
                                             "middle-left", "centre",       "middle-right",
                                             "back-left",   "back-centre",  "back-right"};
    return {fmt::format("friction-ratio residual is {:+.3f} on the {} tile and {:+.3f} on the {} "
                        "tile of a 3 x 3 grid "
                        "over the stroked area",
                        m[hi], kTile[hi], m[lo], kTile[lo]),
            "friction varies over the surface", !(m[hi] - m[lo] > 0.03)};
  }
};
}  // namespace
std::unique_ptr<Effect> MakePositionDependentFriction() {
  return std::make_unique<PositionDependentFriction>();
}
}  // namespace hapticlab::modeling::wb
