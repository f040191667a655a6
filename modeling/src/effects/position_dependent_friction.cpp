// position-dependent-friction: the friction coefficient varies over the surface.
#include <Eigen/Dense>
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

// The simulator's field (its truth, TruthSpecs), u, w in [-1, 1]: not of the model's form.
double TruthField(double u, double w) {
  return 0.8 * u - 0.5 * w + 0.6 * u * w - 0.4 * (1.5 * u * u - 0.5);
}

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
  // Truth: a quadratic field over the stroked square, u, w its coordinates scaled to [-1, 1].
  std::vector<ParamSpec> TruthSpecs() const override {
    return {{.name = std::string(truth_key::kTileAmplitude.name),
             .unit = "1",
             .init = 0.25,
             .lo = 0,
             .hi = 0.9,
             .doc = "mu varies by about +- this over the area"}};
  }
  void TruthFriction(const double* p, const TruthSample& s, TruthFrictionTerms& t) const override {
    t.mu_scale *= 1 + p[0] * TruthField(s.u, s.w);
  }
  void TruthToModel(const double* p, double half_side_m, Model* m) const override {
    // The field is a quadratic in x, y: re-expand it exactly on the model's box by least
    // squares on a grid.
    const double x0 = m->Get(key::kTileX0_m, 0), x1 = m->Get(key::kTileX1_m, 0),
                 y0 = m->Get(key::kTileY0_m, 0), y1 = m->Get(key::kTileY1_m, 0);
    Eigen::MatrixXd A(121, 8);
    Eigen::VectorXd b(121);
    int row = 0;
    for (int i = 0; i <= 10; ++i)
      for (int j = 0; j <= 10; ++j, ++row) {
        const double us = -1 + i / 5.0, vs = -1 + j / 5.0;
        const double x = x0 + (us + 1) / 2 * (x1 - x0), y = y0 + (vs + 1) / 2 * (y1 - y0);
        b(row) = p[0] * TruthField(x / half_side_m, y / half_side_m);
        const double cu[3] = {1, us, 1.5 * us * us - 0.5}, cv[3] = {1, vs, 1.5 * vs * vs - 0.5};
        int c = 0;
        for (int jj = 0; jj <= kOrder; ++jj)
          for (int kk = 0; kk <= kOrder; ++kk)
            if (jj || kk) A(row, c++) = cu[jj] * cv[kk];
      }
    const Eigen::VectorXd g = A.colPivHouseholderQr().solve(b);
    auto& pp = m->params[std::string(effect::kPositionDependentFriction)];
    int c = 0;
    for (int jj = 0; jj <= kOrder; ++jj)
      for (int kk = 0; kk <= kOrder; ++kk)
        if (jj || kk) pp[fmt::format("{}{}{}", kLegendrePrefix, jj, kk)] = g(c++);
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
