// The neural models' linear parts (issue #33): their stability over the conditions they play
// (the largest pole radius over the training grid's rectangle), Γ_U's condition basis sized to
// the grid, and the per-cell AR order (neural_internal.hpp, neural.hpp).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/vibration.hpp"
#include "neural_internal.hpp"

namespace hapticlab::modeling {
namespace neural_internal {

// The degrees in (v', f') of the terms of renderer/neural.hpp's condition basis, in its order
// (1, v', f', v'^2, v' f', f'^2, v'^2 f', v' f'^2, v'^2 f'^2).
constexpr int kDegV[kConditionTerms] = {0, 1, 0, 2, 1, 0, 2, 1, 2};
constexpr int kDegF[kConditionTerms] = {0, 0, 1, 0, 1, 2, 1, 2, 2};

std::array<bool, kConditionTerms> ActiveConditionTerms(std::size_t speeds, std::size_t forces) {
  // A polynomial of degree d in one variable is determined by d + 1 values along it: the
  // tensor basis of degrees min(n - 1, 2) has exactly as many terms as a grid of up to 3 x 3
  // nodes (2 x 2: bilinear, 4 terms; 3 x 2: 6; 3 x 3: the biquadratic 9).
  const int dv = static_cast<int>(std::min<std::size_t>(speeds, 3)) - 1;
  const int df = static_cast<int>(std::min<std::size_t>(forces, 3)) - 1;
  std::array<bool, kConditionTerms> on{};
  for (std::size_t t = 0; t < on.size(); ++t) on[t] = kDegV[t] <= dv && kDegF[t] <= df;
  return on;
}

int PerCellArOrder(const std::vector<std::vector<double>>& train, int M,
                   const VibrationFitOptions& pre) {
  // Why not M = 50 itself: the LSFs of a high-order fit are mostly spurious pairs, and a
  // resonance that moves between two cells changes which LSF pair carries it, so mixing them
  // splits it into two weaker ones instead of moving it (held out on the AR grids, data seed 40:
  // E_s 0.265 and 0.318 with order 50, LPC 0.222 and 0.276).
  const int pmax = pre.order > 0 ? std::min(M, pre.order) : std::min(M, pre.max_order);
  if (pre.order > 0) return pmax;
  std::vector<double> crit(static_cast<std::size_t>(pmax), 0.0);
  for (const auto& x : train)
    for (int p = 1; p <= pmax; ++p)
      crit[static_cast<std::size_t>(p - 1)] += FitAr(x, p, pmax, pre.criterion).criterion;
  return 1 +
         static_cast<int>(std::distance(crit.begin(), std::min_element(crit.begin(), crit.end())));
}

Eigen::VectorXd ConditionBasis(double v, double f, Eigen::Index terms) {
  Eigen::VectorXd phi(kConditionTerms);
  phi << 1, v, f, v * v, v * f, f * f, v * v * f, v * f * f, v * v * f * f;
  return phi.head(terms);
}

namespace {
// Every pole of A(z) = 1 - sum c_i z^-i inside |z| < r: the coefficients c_i / r^i (the poles
// divided by r) are a stable filter.
bool PolesInside(std::span<const double> c, double r, std::vector<double>& work) {
  work.resize(c.size());
  double s = 1;
  for (std::size_t i = 0; i < c.size(); ++i) work[i] = c[i] / (s *= r);
  return renderer::IsStableAr(work);
}
}  // namespace

double MaxPoleRadius(std::span<const double> c) {
  if (c.empty()) return 0;
  std::vector<double> work;
  double lo = 0, hi = 1;
  while (!PolesInside(c, hi, work) && hi < 1e6) lo = hi, hi *= 2;
  for (int k = 0; k < 50 && hi - lo > 1e-12 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (PolesInside(c, mid, work) ? hi : lo) = mid;
  }
  return hi;
}

NeuralPoleRadius ConditionBasisMaxRadius(const Eigen::MatrixXd& W, int n) {
  NeuralPoleRadius out;
  std::vector<double> work;
  const int steps = std::max(n, 2) - 1;
  for (int iv = 0; iv <= steps; ++iv)
    for (int jf = 0; jf <= steps; ++jf) {
      const double v = -1 + 2.0 * iv / steps, f = -1 + 2.0 * jf / steps;
      const Eigen::VectorXd a = W * ConditionBasis(v, f, W.cols());
      const std::span<const double> c(a.data(), static_cast<std::size_t>(a.size()));
      if (out.radius > 0 && PolesInside(c, out.radius, work)) continue;
      const double r = MaxPoleRadius(c);
      if (r > out.radius) out = {r, v, f};
    }
  return out;
}

void RequireStableLinearParts(const renderer::NeuralModel& m,
                              const std::function<void(const std::string&)>& note) {
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    const auto hull = NeuralMaxPoleRadius(m, b);
    note(fmt::format("band {}: largest pole radius of the linear part over the grid {:.4f}", b + 1,
                     hull.radius));
    if (!(hull.radius < 1))
      throw InputError(
          "", 0, "recordings",
          fmt::format("the neural model cannot be made stable: band {} ({}-{} Hz)'s linear part "
                      "has a pole at radius {:.4f} at {} m/s, {} N; refused (an unstable filter "
                      "would drive the actuator to saturation)",
                      b + 1, m.bands[b].lo_hz, m.bands[b].hi_hz, hull.radius, hull.speed_mps,
                      hull.force_N));
  }
}

}  // namespace neural_internal

NeuralPoleRadius NeuralMaxPoleRadius(const renderer::NeuralModel& m, std::size_t band, int n) {
  using namespace neural_internal;  // NOLINT(google-build-using-namespace)
  const auto& b = m.bands.at(band);
  const auto M = static_cast<std::size_t>(b.history);
  const bool unified = m.topology == renderer::NeuralTopology::kUnified;
  // The bank's interpolation over the grid: LSF mixing of cell_ar (Γ_U, format 2), or only
  // its bilinear weights (Γ_D: the cells' networks' outputs, hence their linear weights, mix
  // linearly).
  renderer::VibrationBank bank;
  bank.sample_rate_hz = m.sample_rate_hz / b.decimation;
  bank.grid_speeds_mps = m.speeds_mps;
  bank.grid_forces_N = m.forces_N;
  bank.min_speed_mps = 0;
  const std::size_t nf = m.forces_N.size();
  for (std::size_t c = 0; c < m.speeds_mps.size() * nf; ++c) {
    renderer::ArCell cell;
    cell.speed_mps = m.speeds_mps[c / nf];
    cell.force_N = m.forces_N[c % nf];
    if (!b.cell_ar.empty()) {
      cell.coeffs = b.cell_ar[c];
      cell.lsf = b.cell_lsf.empty() ? renderer::ArToLsf(cell.coeffs) : b.cell_lsf[c];
    }
    bank.cells.push_back(std::move(cell));
  }
  renderer::VibrationInterpolator interp(bank);
  NeuralPoleRadius out;
  std::vector<double> c(M), work;
  const int steps = std::max(n, 2) - 1;
  for (int iv = 0; iv <= steps; ++iv)
    for (int jf = 0; jf <= steps; ++jf) {
      const double v = m.speeds_mps.front() +
                       (m.speeds_mps.back() - m.speeds_mps.front()) * iv / steps,
                   f = m.forces_N.front() + (m.forces_N.back() - m.forces_N.front()) * jf / steps;
      std::fill(c.begin(), c.end(), 0.0);
      if (!b.cell_ar.empty()) {
        renderer::ArFilter filter;
        interp.Interpolate(v, f, true, &filter);
        std::copy_n(filter.c.begin(), filter.order, c.begin());
      } else if (unified) {
        const auto& w = b.nets.front().linear;
        if (w.empty()) continue;
        const auto terms = static_cast<Eigen::Index>(w.size() / M);
        const Eigen::Map<const Eigen::MatrixXd> W(w.data(), static_cast<Eigen::Index>(M), terms);
        const Eigen::VectorXd a = W * ConditionBasis(m.NormSpeed(v), m.NormForce(f), terms);
        std::copy_n(a.data(), M, c.begin());
      } else {
        const auto cw = interp.Weights(v, f);
        for (int k = 0; k < cw.count; ++k) {
          const auto& w =
              b.nets[static_cast<std::size_t>(cw.cell[static_cast<std::size_t>(k)])].linear;
          for (std::size_t i = 0; i < w.size() && i < M; ++i)
            c[i] += cw.weight[static_cast<std::size_t>(k)] * w[i];
        }
      }
      // Most points are inside the largest radius found so far: one stability check each.
      if (out.radius > 0 && PolesInside(c, out.radius, work)) continue;
      const double r = MaxPoleRadius(c);
      if (r > out.radius) out = {r, v, f};
    }
  return out;
}

}  // namespace hapticlab::modeling
