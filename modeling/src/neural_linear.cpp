// Γ_U's and Γ_D's linear parts (neural_fit.hpp): least squares on a network's clean rows, as a
// condition basis or, as Γ_U's stability fallback, per-cell AR fits mixed in LSF form.

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <span>

#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "neural_fit.hpp"
#include "neural_internal.hpp"

namespace hapticlab::modeling::neural_fit {

using namespace neural_internal;  // NOLINT(google-build-using-namespace): FitNeural's own helpers

namespace {

// Per used recording (as laid out in X): the Gram matrix and moment vector of its rows.
struct Grams {
  std::vector<Eigen::MatrixXd> G;
  std::vector<Eigen::VectorXd> g;
};
Grams RecordingGrams(const FitShared& s, const Job& j, const JobRows& rows, Eigen::Index p,
                     bool all_rows) {
  Grams out{std::vector<Eigen::MatrixXd>(rows.use.size(), Eigen::MatrixXd::Zero(p, p)),
            std::vector<Eigen::VectorXd>(rows.use.size(), Eigen::VectorXd::Zero(p))};
  Eigen::Index off = 0;
  for (const bool val : {false, true})
    for (std::size_t u = 0; u < rows.use.size(); ++u) {
      const auto [a, b] = s.RowsOf(j, rows.use[u], val);
      const auto n = static_cast<Eigen::Index>(b - a);
      if (!val || all_rows) {
        const auto Xi = rows.X.block(off, 0, n, p);
        out.G[u] += Xi.transpose() * Xi;
        out.g[u] += Xi.transpose() * rows.y.segment(off, n);
      }
      off += n;
    }
  return out;
}

// Per-cell AR(p_lin) fits, each on its own recording's rows (ridge-regularized least squares;
// the Levinson fit where that is not minimum phase, as LSF mixing needs).
void FitPerCell(const FitShared& s, const Job& j, const JobRows& rows, const LinearForm& form,
                Grams grams, bool all_rows, LinearFit* f) {
  const Eigen::Index p = form.p_lin;
  for (std::size_t u = 0; u < rows.use.size(); ++u) {
    const auto i = rows.use[u];
    const auto c = static_cast<std::size_t>(s.cell_of[i]);
    auto& G = grams.G[u];
    G.diagonal().array() += s.o.linear_ridge * G.trace() / static_cast<double>(p);
    f->a_cell[c].head(p) = G.ldlt().solve(grams.g[u]);
    if (!renderer::IsStableAr(
            std::span<const double>(f->a_cell[c].data(), static_cast<std::size_t>(p)))) {
      // The covariance-method fit need not be minimum phase, and LSF mixing needs it: the
      // autocorrelation method (Levinson, as the LPC bank) always is.
      const auto& x = s.sig[j.band][i];
      const auto end = all_rows ? x.size() : s.RowsOf(j, i, false).second;
      const auto fit =
          FitAr(std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(end)),
                static_cast<int>(p));
      f->a_cell[c].head(p) = Eigen::Map<const Eigen::VectorXd>(fit.coeffs.data(), p);
      s.Progress(
          fmt::format("band {}: the least-squares AR({}) at {} m/s, {} N is not minimum "
                      "phase; the Levinson fit is used there",
                      j.band + 1, p, s.recs[i].speed_mps, s.recs[i].force_N));
    }
  }
  for (const auto& a : f->a_cell) f->cell_ar.emplace_back(a.data(), a.data() + p);
  f->w.resize(0);  // the network itself has no linear weights
}

// The condition basis: features phi(v', f') (x) x (Γ_D: phi = 1; Γ_U: the basis, with no more
// terms than the grid has nodes; the terms ActiveConditionTerms leaves out are fitted as zero),
// phi constant within a recording: the normal matrix is the sum over recordings of
// (phi phi^T) (x) (X_i^T X_i).
void FitConditionBasis(const FitShared& s, const Job& j, const JobRows& rows,
                       const LinearForm& form, const Grams& grams, bool all_rows, LinearFit* f) {
  const int M = rows.M;
  const Eigen::Index terms = form.terms, nlin = form.nlin;
  const auto active = ActiveConditionTerms(s.m.speeds_mps.size(), s.nf);
  auto phi_of = [&](std::size_t i) {
    return s.unified ? ConditionBasis(s.m.NormSpeed(s.recs[i].speed_mps),
                                      s.m.NormForce(s.recs[i].force_N), terms)
                     : ConditionBasis(0, 0, terms);
  };
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(nlin, nlin);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nlin);
  for (std::size_t u = 0; u < rows.use.size(); ++u) {
    const Eigen::VectorXd phi = phi_of(rows.use[u]);
    for (Eigen::Index t = 0; t < terms; ++t) {
      rhs.segment(t * M, M) += phi(t) * grams.g[u];
      for (Eigen::Index q = 0; q < terms; ++q)
        A.block(t * M, q * M, M, M) += (phi(t) * phi(q)) * grams.G[u];
    }
  }
  A.diagonal().array() += s.o.linear_ridge * A.trace() / static_cast<double>(nlin);
  for (Eigen::Index t = 0; t < terms; ++t)
    if (terms > 1 && !active[static_cast<std::size_t>(t)]) {  // fitted as zero
      A.middleRows(t * M, M).setZero();
      A.middleCols(t * M, M).setZero();
      A.block(t * M, t * M, M, M).setIdentity();
      rhs.segment(t * M, M).setZero();
    }
  f->w = A.ldlt().solve(rhs);
  if (!s.unified && !renderer::IsStableAr(std::span<const double>(f->w.data(), M))) {
    // Γ_D's covariance-method fit at its cell need not be minimum phase: Levinson's is.
    const auto& x = s.sig[j.band][rows.use.front()];
    const auto end = all_rows ? x.size() : s.RowsOf(j, rows.use.front(), false).second;
    f->w = Eigen::Map<const Eigen::VectorXd>(
        FitAr(std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(end)), M)
            .coeffs.data(),
        M);
  }
  // The AR coefficients at each training cell: the M x terms weights times phi.
  const Eigen::Map<const Eigen::MatrixXd> W(f->w.data(), M, terms);
  for (const auto i : rows.use) f->a_cell[static_cast<std::size_t>(s.cell_of[i])] = W * phi_of(i);
}

// The per-cell AR order: as the LPC bank chooses its order (PerCellArOrder).
Eigen::Index PerCellOrder(const FitShared& s, const Job& j, const JobRows& rows) {
  std::vector<std::vector<double>> train;
  for (const auto i : rows.use) {
    const auto& x = s.sig[j.band][i];
    train.emplace_back(x.begin(),
                       x.begin() + static_cast<std::ptrdiff_t>(s.RowsOf(j, i, false).second));
  }
  const Eigen::Index p = PerCellArOrder(train, rows.M, s.o.preprocess);
  s.Progress(fmt::format("band {}: per-cell AR order {} (as the LPC bank chooses)", j.band + 1, p));
  return p;
}

}  // namespace

// The linear part: least squares on the clean rows; either way the linear part at a training
// cell is one AR(M), `a_cell[c]`.
LinearFit FitLinear(const FitShared& s, const Job& j, const JobRows& rows, const LinearForm& form,
                    bool all_rows) {
  LinearFit f{Eigen::VectorXd::Zero(form.nlin),
              std::vector<Eigen::VectorXd>(s.cells, Eigen::VectorXd::Zero(rows.M)),
              {},
              Eigen::VectorXd::Zero(rows.total)};
  if (form.nlin == 0) return f;
  const Eigen::Index p = form.per_cell ? form.p_lin : rows.M;
  auto grams = RecordingGrams(s, j, rows, p, all_rows);
  if (form.per_cell)
    FitPerCell(s, j, rows, form, std::move(grams), all_rows, &f);
  else
    FitConditionBasis(s, j, rows, form, grams, all_rows, &f);
  for (Eigen::Index r = 0; r < rows.total; ++r)
    f.ylin(r) =
        rows.X.row(r).head(rows.M).dot(f.a_cell[rows.row_cell[static_cast<std::size_t>(r)]]);
  return f;
}

// The linear part on the training rows, stable wherever the model plays, at fit time: Γ_U's
// condition basis is checked over a fine grid of the hull; where its largest pole radius is not
// below NeuralFitOptions::max_condition_basis_radius (at most 1), the band is fitted per cell
// and mixed in LSF form instead (stable by construction) before the network learns what the
// linear part leaves.
LinearFit FitStableLinear(const FitShared& s, const Job& j, const JobRows& rows, LinearForm* form) {
  form->per_cell = false;
  form->terms = s.unified ? 9 : 1;
  form->nlin = s.o.linear_part ? form->terms * rows.M : 0;
  form->p_lin = rows.M;
  LinearFit lin = FitLinear(s, j, rows, *form, false);
  if (!s.unified || form->nlin == 0) return lin;
  const double limit = std::min(1.0, s.o.max_condition_basis_radius);
  const auto hull =
      ConditionBasisMaxRadius(Eigen::Map<const Eigen::MatrixXd>(lin.w.data(), rows.M, form->terms));
  if (hull.radius < limit) return lin;
  s.Progress(
      fmt::format("band {}: the condition basis has a pole at radius {:.3f} (limit "
                  "{:.3g}); fitted per cell and mixed in LSF form instead",
                  j.band + 1, hull.radius, limit));
  form->per_cell = true, form->terms = 1, form->nlin = rows.M;
  form->p_lin = PerCellOrder(s, j, rows);
  return FitLinear(s, j, rows, *form, false);
}

}  // namespace hapticlab::modeling::neural_fit
