// Kenward-Roger small-sample inference for linear mixed models (Kenward & Roger 1997,
// Biometrics 53:983-997), as pbkrtest 0.5 computes it (vcovAdj_internal, .KR_adjust, Lb_ddf)
// and lmerTest reports it (ddf = "Kenward-Roger"). Hand-written: no C/C++ library for it is
// packaged. The covariance V = Σ_r γ_r G_r is linear in the variance-covariance elements γ
// (each random term's lower triangle, then σ²), G_r = ∂V/∂γ_r.
//
// pbkrtest forms V⁻¹ and every G_r V⁻¹ as dense n x n matrices. Here nothing is n x n: each
// G_r but the last is Z S_r Z' with S_r a 0/1 selector in the space of the q random effects,
// the last is I, and V = σ² I + U U' with U = Z D^½ (D = cov(b), block diagonal). By Woodbury,
// V⁻¹ maps the columns of B = [Z X] into their own span: V⁻¹ B = B T with a (q+p) x (q+p) T,
// so every product pbkrtest needs (X'V⁻¹G_rV⁻¹X, X'V⁻¹G_rV⁻¹G_sV⁻¹X, tr(G_rV⁻¹G_sV⁻¹)) is a
// product of q- and p-sized matrices: memory O((q+p)²), time O((q+p)³), whatever n is.

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "lmm_design.hpp"

namespace hapticlab::stats::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using SpMat = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;

namespace {

// V = σ² I + Z D Z' seen through B = [Z X]: the Gram products B'V⁻ᵏB (k = 1, 2, 3) and
// tr(V⁻²), the only places where n enters.
struct WoodburyProducts {
  MatrixXd K, K2;  ///< Z'V⁻¹Z, Z'V⁻²Z (q x q)
  MatrixXd R, R2;  ///< Z'V⁻¹X, Z'V⁻²X (q x p)
  MatrixXd XV2X, XV3X;
  double trace_V2 = 0;
};

WoodburyProducts Products(const LmmDesign& d, const SpMat& root_d, double sigma2) {
  const Index n = d.X.rows(), p = d.X.cols(), q = d.Z.cols();
  const MatrixXd ZtZ(SpMat(d.Z.transpose() * d.Z));
  MatrixXd gram(q + p, q + p);  // B'B
  gram.topLeftCorner(q, q) = ZtZ;
  gram.topRightCorner(q, p) = d.Z.transpose() * d.X;
  gram.bottomLeftCorner(p, q) = gram.topRightCorner(q, p).transpose();
  gram.bottomRightCorner(p, p) = d.X.transpose() * d.X;
  // Woodbury: V⁻¹ = σ⁻² (I - U C⁻¹ U'), C = σ² I + U'U, U = Z D^½ (D^½ symmetric).
  const MatrixXd A = root_d * (ZtZ * root_d);  // U'U
  MatrixXd C = A;
  C.diagonal().array() += sigma2;
  const Eigen::LLT<MatrixXd> llt(C);
  const MatrixXd CiA = llt.solve(A);
  const MatrixXd M = root_d * llt.solve(MatrixXd(root_d));  // D^½ C⁻¹ D^½
  // V⁻¹ B = B T: T = σ⁻² (I - [M Z'B; 0]).
  MatrixXd T = MatrixXd::Identity(q + p, q + p);
  T.topRows(q) -= M * gram.topRows(q);
  T /= sigma2;
  const MatrixXd GT = gram * T, GT2 = GT * T;
  WoodburyProducts w;
  w.K = GT.topLeftCorner(q, q);
  w.K2 = GT2.topLeftCorner(q, q);
  w.R = GT.topRightCorner(q, p);
  w.R2 = GT2.topRightCorner(q, p);
  w.XV2X = GT2.bottomRightCorner(p, p);
  w.XV3X = GT2.bottomRows(p) * T.rightCols(p);
  w.trace_V2 =
      (static_cast<double>(n) - 2.0 * CiA.trace() + CiA.cwiseProduct(CiA.transpose()).sum()) /
      (sigma2 * sigma2);
  return w;
}

// tr(S_r K S_s K) over the nonzeros of the two selectors (each has a few per level).
double TraceSKSK(const SpMat& Sr, const MatrixXd& K, const SpMat& Ss) {
  double t = 0;
  for (Index a = 0; a < Sr.outerSize(); ++a)
    for (SpMat::InnerIterator i(Sr, a); i; ++i)
      for (Index c = 0; c < Ss.outerSize(); ++c)
        for (SpMat::InnerIterator j(Ss, c); j; ++j)
          t += i.value() * K(i.col(), j.row()) * j.value() * K(j.col(), i.row());
  return t;
}

// tr(S_r K) over the nonzeros of the selector.
double TraceSK(const SpMat& Sr, const MatrixXd& K) {
  double t = 0;
  for (Index a = 0; a < Sr.outerSize(); ++a)
    for (SpMat::InnerIterator i(Sr, a); i; ++i) t += i.value() * K(i.col(), i.row());
  return t;
}

// The selectors S_r (G_r = Z S_r Z') of each term's covariance elements (i, j): ones at (i, j)
// and (j, i) of every level's block; and D^½, the symmetric square root of D = cov(b).
void Selectors(const LmmDesign& d, const std::vector<double>& gamma, std::vector<SpMat>& S,
               SpMat& root_d) {
  const Index q = d.Z.cols();
  std::vector<Triplet> root;
  std::size_t r = 0;
  for (const auto& b : d.blocks) {
    MatrixXd Db(b.p, b.p);
    for (int j = 0; j < b.p; ++j)
      for (int i = j; i < b.p; ++i, ++r) {
        Db(i, j) = Db(j, i) = gamma[r];
        std::vector<Triplet> t;
        for (int l = 0; l < b.levels; ++l) {
          const int base = b.offset + l * b.p;
          t.emplace_back(base + i, base + j, 1.0);
          if (i != j) t.emplace_back(base + j, base + i, 1.0);
        }
        SpMat s(q, q);
        s.setFromTriplets(t.begin(), t.end());
        S.push_back(s);
      }
    const Eigen::SelfAdjointEigenSolver<MatrixXd> e(Db);
    const MatrixXd half = e.eigenvectors() *
                          e.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                          e.eigenvectors().transpose();
    for (int l = 0; l < b.levels; ++l)
      for (int j = 0; j < b.p; ++j)
        for (int i = 0; i < b.p; ++i)
          if (half(i, j) != 0.0)
            root.emplace_back(b.offset + l * b.p + i, b.offset + l * b.p + j, half(i, j));
  }
  root_d.resize(q, q);
  root_d.setFromTriplets(root.begin(), root.end());
}

}  // namespace

KrAdjusted KenwardRogerVcov(const LmmDesign& d, const std::vector<double>& gamma,
                            const MatrixXd& Phi) {
  std::vector<SpMat> S;
  SpMat root_d;
  Selectors(d, gamma, S, root_d);
  const auto w = Products(d, root_d, gamma.back());
  const std::size_t m = S.size() + 1;  // the last G is I (the σ² element)
  std::vector<MatrixXd> SR;            // S_r Z'V⁻¹X
  for (const auto& s : S) SR.push_back(s * w.R);
  KrAdjusted a;
  // P_r = -X'V⁻¹G_rV⁻¹X; Q_rs = X'V⁻¹G_rV⁻¹G_sV⁻¹X (s ≥ r); tr(G_rV⁻¹G_sV⁻¹).
  std::vector<std::vector<MatrixXd>> Q(m, std::vector<MatrixXd>(m));
  MatrixXd ktrace(static_cast<Index>(m), static_cast<Index>(m));
  for (std::size_t r = 0; r < m; ++r) {
    const MatrixXd P = r + 1 == m ? MatrixXd(-w.XV2X) : MatrixXd(-w.R.transpose() * SR[r]);
    a.P.push_back(0.5 * (P + P.transpose()));
    for (std::size_t s = r; s < m; ++s) {
      double k = 0;
      if (r + 1 == m) {
        Q[r][s] = w.XV3X;
        k = w.trace_V2;
      } else if (s + 1 == m) {
        Q[r][s] = SR[r].transpose() * w.R2;
        k = TraceSK(S[r], w.K2);
      } else {
        Q[r][s] = SR[r].transpose() * w.K * SR[s];
        k = TraceSKSK(S[r], w.K, S[s]);
      }
      ktrace(static_cast<Index>(r), static_cast<Index>(s)) = k;
    }
  }
  MatrixXd IE2(static_cast<Index>(m), static_cast<Index>(m));
  for (std::size_t r = 0; r < m; ++r) {
    const MatrixXd PhiP = Phi * a.P[r];
    for (std::size_t s = r; s < m; ++s) {
      const double v = ktrace(static_cast<Index>(r), static_cast<Index>(s)) -
                       2.0 * Phi.cwiseProduct(Q[r][s]).sum() +
                       PhiP.cwiseProduct(a.P[s] * Phi).sum();
      IE2(static_cast<Index>(r), static_cast<Index>(s)) = v;
      IE2(static_cast<Index>(s), static_cast<Index>(r)) = v;
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
    for (Index i = 0; i < inv.size(); ++i) inv[i] = std::abs(inv[i]) > tol ? 1.0 / inv[i] : 0.0;
    a.W = 2.0 * eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  }
  const Index p = d.X.cols();
  MatrixXd U = MatrixXd::Zero(p, p);
  for (std::size_t r = 0; r + 1 < m; ++r)
    for (std::size_t s = r + 1; s < m; ++s)
      U += a.W(static_cast<Index>(r), static_cast<Index>(s)) * (Q[r][s] - a.P[r] * Phi * a.P[s]);
  U = MatrixXd(U + U.transpose());
  for (std::size_t r = 0; r < m; ++r)
    U += a.W(static_cast<Index>(r), static_cast<Index>(r)) * (Q[r][r] - a.P[r] * Phi * a.P[r]);
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
      const double w = a.W(static_cast<Index>(i), static_cast<Index>(j));
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
