// Kenward-Roger small-sample inference for linear mixed models (Kenward & Roger 1997,
// Biometrics 53:983-997), as pbkrtest 0.5 computes it (vcovAdj_internal, .KR_adjust, Lb_ddf)
// and lmerTest reports it (ddf = "Kenward-Roger"). Hand-written: no C/C++ library for it is
// packaged. The covariance V = Σ_r γ_r G_r is linear in the variance-covariance elements γ
// (each random term's lower triangle, then σ²), G_r = ∂V/∂γ_r. Dense n x n matrices: the
// caller limits n.

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "lmm_design.hpp"

namespace hapticlab::stats::detail {

using Eigen::MatrixXd;
using SpMat = Eigen::SparseMatrix<double>;

KrAdjusted KenwardRogerVcov(const LmmDesign& d, const std::vector<double>& gamma,
                            const MatrixXd& Phi) {
  const Eigen::Index n = d.X.rows();
  // G_r: for term k and element (i, j) of its covariance, Z_i Z_j' + Z_j Z_i' (i ≠ j) or
  // Z_i Z_i', where Z_i holds column i of the term for every level.
  std::vector<SpMat> G;
  for (const auto& b : d.blocks) {
    std::vector<SpMat> Zc;
    for (int i = 0; i < b.p; ++i) {
      std::vector<Eigen::Triplet<double>> t;
      for (int l = 0; l < b.levels; ++l) {
        const int col = b.offset + l * b.p + i;
        for (SpMat::InnerIterator it(d.Z, col); it; ++it)
          t.emplace_back(static_cast<int>(it.row()), l, it.value());
      }
      SpMat z(n, b.levels);
      z.setFromTriplets(t.begin(), t.end());
      Zc.push_back(z);
    }
    for (int j = 0; j < b.p; ++j)
      for (int i = j; i < b.p; ++i) {
        SpMat g =
            Zc[static_cast<std::size_t>(i)] * SpMat(Zc[static_cast<std::size_t>(j)].transpose());
        if (i != j) g = SpMat(g + SpMat(g.transpose()));
        G.push_back(g);
      }
  }
  SpMat I(n, n);
  I.setIdentity();
  G.push_back(I);
  const std::size_t m = G.size();
  MatrixXd V = MatrixXd::Zero(n, n);
  for (std::size_t r = 0; r < m; ++r) V += gamma[r] * MatrixXd(G[r]);
  const MatrixXd Vinv = V.llt().solve(MatrixXd::Identity(n, n));
  const MatrixXd TT = Vinv * d.X;
  std::vector<MatrixXd> H(m), O(m);
  for (std::size_t r = 0; r < m; ++r) {
    H[r] = G[r] * Vinv;
    O[r] = H[r] * d.X;
  }
  KrAdjusted a;
  std::vector<std::vector<MatrixXd>> Q(m, std::vector<MatrixXd>(m));
  for (std::size_t r = 0; r < m; ++r) {
    MatrixXd P = -O[r].transpose() * TT;
    a.P.push_back(0.5 * (P + P.transpose()));
    const MatrixXd OrV = O[r].transpose() * Vinv;
    for (std::size_t s = r; s < m; ++s) Q[r][s] = OrV * O[s];
  }
  MatrixXd IE2(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  for (std::size_t r = 0; r < m; ++r) {
    const MatrixXd PhiP = Phi * a.P[r];
    for (std::size_t s = r; s < m; ++s) {
      const double ktrace = H[r].transpose().cwiseProduct(H[s]).sum();
      const double v =
          ktrace - 2.0 * Phi.cwiseProduct(Q[r][s]).sum() + PhiP.cwiseProduct(a.P[s] * Phi).sum();
      IE2(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = v;
      IE2(static_cast<Eigen::Index>(s), static_cast<Eigen::Index>(r)) = v;
    }
  }
  Eigen::SelfAdjointEigenSolver<MatrixXd> eig(IE2);
  const double condi = eig.eigenvalues().cwiseAbs().minCoeff();
  if (condi > 1e-10) {
    a.W = 2.0 * IE2.inverse();
  } else {  // pbkrtest: 2 * MASS::ginv(IE2)
    Eigen::VectorXd inv = eig.eigenvalues();
    const double tol =
        std::sqrt(std::numeric_limits<double>::epsilon()) * eig.eigenvalues().cwiseAbs().maxCoeff();
    for (Eigen::Index i = 0; i < inv.size(); ++i)
      inv[i] = std::abs(inv[i]) > tol ? 1.0 / inv[i] : 0.0;
    a.W = 2.0 * eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  }
  const Eigen::Index p = d.X.cols();
  MatrixXd U = MatrixXd::Zero(p, p);
  for (std::size_t r = 0; r + 1 < m; ++r)
    for (std::size_t s = r + 1; s < m; ++s)
      U += a.W(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) *
           (Q[r][s] - a.P[r] * Phi * a.P[s]);
  U = MatrixXd(U + U.transpose());
  for (std::size_t r = 0; r < m; ++r)
    U += a.W(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) *
         (Q[r][r] - a.P[r] * Phi * a.P[r]);
  a.PhiA = Phi + 2.0 * Phi * U * Phi;
  return a;
}

KrTest KenwardRogerTest(const KrAdjusted& a, const MatrixXd& Phi, const MatrixXd& L,
                        const Eigen::VectorXd& beta) {
  const MatrixXd Theta = L.transpose() * (L * Phi * L.transpose()).ldlt().solve(L);
  const MatrixXd ThetaPhi = Theta * Phi;
  double A1 = 0, A2 = 0;
  const std::size_t m = a.P.size();
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = i; j < m; ++j) {
      const double e = i == j ? 1.0 : 2.0;
      const MatrixXd ui = ThetaPhi * a.P[i] * Phi;
      const MatrixXd uj = ThetaPhi * a.P[j] * Phi;
      const double w = a.W(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      A1 += e * w * ui.trace() * uj.trace();
      A2 += e * w * ui.cwiseProduct(uj.transpose()).sum();
    }
  const double q = static_cast<double>(L.rows());
  const double B = (A1 + 6 * A2) / (2 * q);
  const double g = ((q + 1) * A1 - (q + 4) * A2) / ((q + 2) * A2);
  const double c1 = g / (3 * q + 2 * (1 - g));
  const double c2 = (q - g) / (3 * q + 2 * (1 - g));
  const double c3 = (q + 2 - g) / (3 * q + 2 * (1 - g));
  double V0 = 1 + c1 * B;
  const double V1 = 1 - c2 * B;
  const double V2 = 1 - c3 * B;
  if (std::abs(V0) < 1e-10) V0 = 0;
  const double x = 1 - A2 / q;
  const double ratio =
      (std::abs(x) < 1e-14 && std::abs(V1) < 1e-14) ? 1.0 : x / V1;  // pbkrtest's .divZero
  const double rho = ratio * ratio * V0 / V2 / q;
  KrTest t;
  t.ddf = 4 + (q + 2) / (q * rho - 1);
  t.scaling = std::abs(t.ddf - 2) < 0.01 ? 1.0 : t.ddf * (1 - A2 / q) / (t.ddf - 2);
  const Eigen::VectorXd Lb = L * beta;
  const double wald = Lb.dot((L * a.PhiA * L.transpose()).ldlt().solve(Lb));
  t.F = t.scaling * wald / q;
  return t;
}

}  // namespace hapticlab::stats::detail
