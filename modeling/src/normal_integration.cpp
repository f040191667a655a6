// Heights from normals (normal_integration.hpp): Frankot-Chellappa, DCT Poisson, masked
// Poisson. The transforms are FFTW's and the factorisation Eigen's; the assembly is ours.
#include "hapticlab/modeling/normal_integration.hpp"

#include <fftw3.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;

}  // namespace

std::vector<float> IntegrateNormals(const std::vector<Eigen::Vector3f>& nrm, int w, int h,
                                    double pitch) {
  const int wc = w / 2 + 1;
  static std::mutex mu;  // FFTW planning is not thread-safe
  std::vector<double> p(static_cast<std::size_t>(w) * static_cast<std::size_t>(h)), q(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto& n = nrm[i];
    const double nz = std::max(static_cast<double>(n.z()), 1e-3);
    p[i] = -n.x() / nz;  // dh/dx (height units per pixel unit)
    q[i] = -n.y() / nz;  // dh/dy
  }
  std::vector<std::complex<double>> P(static_cast<std::size_t>(h) * static_cast<std::size_t>(wc)),
      Q(P.size()), Z(P.size());
  std::vector<double> out(p.size());
  fftw_plan fp, fq, iz;
  {
    std::lock_guard lock(mu);
    fp = fftw_plan_dft_r2c_2d(h, w, p.data(), reinterpret_cast<fftw_complex*>(P.data()),
                              FFTW_ESTIMATE);
    fq = fftw_plan_dft_r2c_2d(h, w, q.data(), reinterpret_cast<fftw_complex*>(Q.data()),
                              FFTW_ESTIMATE);
    iz = fftw_plan_dft_c2r_2d(h, w, reinterpret_cast<fftw_complex*>(Z.data()), out.data(),
                              FFTW_ESTIMATE);
  }
  fftw_execute(fp);
  fftw_execute(fq);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < wc; ++u) {
      const double wx = 2 * kPi * u / w, wy = 2 * kPi * (v <= h / 2 ? v : v - h) / h;
      const std::size_t k =
          static_cast<std::size_t>(v) * static_cast<std::size_t>(wc) + static_cast<std::size_t>(u);
      const double d = wx * wx + wy * wy;
      Z[k] = d > 0 ? (std::complex<double>(0, -wx) * P[k] + std::complex<double>(0, -wy) * Q[k]) / d
                   : 0.0;
    }
  fftw_execute(iz);
  {
    std::lock_guard lock(mu);
    fftw_destroy_plan(fp);
    fftw_destroy_plan(fq);
    fftw_destroy_plan(iz);
  }
  std::vector<float> hgt(out.size());
  const double norm = static_cast<double>(w) * static_cast<double>(h);
  for (std::size_t i = 0; i < out.size(); ++i) hgt[i] = static_cast<float>(out[i] / norm * pitch);
  return hgt;
}

namespace {

// Gradients between 4-neighbours from the normals: gx[k] = h(k + 1) - h(k) along a row and
// gy[k] = h(k + W) - h(k) down a column (height units per pixel), each the mean of the two
// pixels' slopes; zero where the pair leaves the image.
void EdgeGradients(const std::vector<Eigen::Vector3f>& nrm, int w, int h, std::vector<double>* gx,
                   std::vector<double>* gy) {
  const auto W = static_cast<std::size_t>(w), H = static_cast<std::size_t>(h);
  std::vector<double> p(W * H), q(W * H);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double nz = std::max(static_cast<double>(nrm[i].z()), 1e-3);
    p[i] = -nrm[i].x() / nz;
    q[i] = -nrm[i].y() / nz;
  }
  gx->assign(W * H, 0.0);
  gy->assign(W * H, 0.0);
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const std::size_t k = i * W + j;
      if (j + 1 < W) (*gx)[k] = 0.5 * (p[k] + p[k + 1]);
      if (i + 1 < H) (*gy)[k] = 0.5 * (q[k] + q[k + W]);
    }
}

// The connected regions (4-neighbour) of the mask's pixels: region[id[k]] for each pixel k
// inside (id: its unknown's index, kOut outside); each region is pinned at its first pixel
// (diag += 1 there). Returns the number of regions.
std::size_t PinRegions(const std::vector<std::uint8_t>& mask, const std::vector<std::size_t>& id,
                       std::size_t W, std::size_t H, std::vector<double>* diag,
                       std::vector<std::size_t>* region_out) {
  constexpr std::size_t kOut = static_cast<std::size_t>(-1);
  const std::size_t N = W * H;
  std::vector<std::size_t>& region = *region_out;
  region.assign(diag->size(), kOut);
  std::vector<std::size_t> stack;
  std::size_t regions = 0;
  for (std::size_t k = 0; k < N; ++k) {
    if (!mask[k] || region[id[k]] != kOut) continue;
    (*diag)[id[k]] += 1;
    region[id[k]] = regions;
    stack.push_back(k);
    while (!stack.empty()) {
      const std::size_t c = stack.back();
      stack.pop_back();
      const std::size_t ci = c / W, cj = c % W;
      const std::size_t nb[4] = {cj + 1 < W ? c + 1 : kOut, cj > 0 ? c - 1 : kOut,
                                 ci + 1 < H ? c + W : kOut, ci > 0 ? c - W : kOut};
      for (auto q : nb)
        if (q != kOut && mask[q] && region[id[q]] == kOut) {
          region[id[q]] = regions;
          stack.push_back(q);
        }
    }
    ++regions;
  }
  return regions;
}

}  // namespace

std::vector<float> IntegrateNormalsPoisson(const std::vector<Eigen::Vector3f>& nrm, int w, int h,
                                           double pitch) {
  // The least-squares height on the 4-neighbour grid: lap z = div g, with the Laplacian's
  // Neumann boundary diagonalised by the DCT-II [Simchony, Chellappa, Shao 1990,
  // doi:10.1109/34.55103].
  const auto W = static_cast<std::size_t>(w), H = static_cast<std::size_t>(h);
  std::vector<double> gx, gy, f(W * H), z(W * H);
  EdgeGradients(nrm, w, h, &gx, &gy);
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const std::size_t k = i * W + j;
      f[k] = gx[k] - (j > 0 ? gx[k - 1] : 0.0) + gy[k] - (i > 0 ? gy[k - W] : 0.0);
    }
  static std::mutex mu;
  fftw_plan fwd, inv;
  {
    std::lock_guard lock(mu);
    fwd = fftw_plan_r2r_2d(h, w, f.data(), z.data(), FFTW_REDFT10, FFTW_REDFT10, FFTW_ESTIMATE);
    inv = fftw_plan_r2r_2d(h, w, z.data(), f.data(), FFTW_REDFT01, FFTW_REDFT01, FFTW_ESTIMATE);
  }
  fftw_execute(fwd);
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const double lam = 2 * std::cos(kPi * static_cast<double>(j) / w) +
                         2 * std::cos(kPi * static_cast<double>(i) / h) - 4;
      z[i * W + j] = (i == 0 && j == 0) ? 0.0 : z[i * W + j] / lam;
    }
  fftw_execute(inv);
  {
    std::lock_guard lock(mu);
    fftw_destroy_plan(fwd);
    fftw_destroy_plan(inv);
  }
  std::vector<float> out(W * H);
  const double norm = 4.0 * static_cast<double>(W) * static_cast<double>(H);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<float>(f[i] / norm * pitch);
  return out;
}

std::vector<float> IntegrateNormalsMasked(const std::vector<Eigen::Vector3f>& nrm,
                                          const std::vector<std::uint8_t>& mask, int w, int h,
                                          double pitch) {
  const auto W = static_cast<std::size_t>(w), H = static_cast<std::size_t>(h), N = W * H;
  HL_REQUIRE(nrm.size() == N && mask.size() == N,
             "normals and mask must have width x height values");
  std::vector<double> gx, gy;
  EdgeGradients(nrm, w, h, &gx, &gy);
  constexpr std::size_t kOut = static_cast<std::size_t>(-1);
  std::vector<std::size_t> id(N, kOut);
  std::size_t n = 0;
  for (std::size_t k = 0; k < N; ++k)
    if (mask[k]) id[k] = n++;
  std::vector<float> out(N, 0.f);
  if (n == 0) return out;
  // Normal equations of sum over inside pairs (z_b - z_a - g_ab)^2: the graph Laplacian.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(5 * n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  std::vector<double> diag(n, 0.0);
  auto edge = [&](std::size_t a, std::size_t c, double g) {
    const auto ia = static_cast<Eigen::Index>(id[a]), ic = static_cast<Eigen::Index>(id[c]);
    trip.emplace_back(ia, ic, -1.0);
    trip.emplace_back(ic, ia, -1.0);
    diag[id[a]] += 1;
    diag[id[c]] += 1;
    rhs[ia] -= g;
    rhs[ic] += g;
  };
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const std::size_t k = i * W + j;
      if (!mask[k]) continue;
      if (j + 1 < W && mask[k + 1]) edge(k, k + 1, gx[k]);
      if (i + 1 < H && mask[k + W]) edge(k, k + W, gy[k]);
    }
  // Connected regions (4-neighbour): each is pinned at its first pixel (adding z^2 there
  // fixes the free constant without changing the rest) and shifted to zero mean afterwards.
  std::vector<std::size_t> region;
  const std::size_t regions = PinRegions(mask, id, W, H, &diag, &region);
  for (std::size_t v = 0; v < n; ++v)
    trip.emplace_back(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(v), diag[v]);
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success)
    throw std::runtime_error("masked Poisson integration: factorisation failed");
  const Eigen::VectorXd z = solver.solve(rhs);
  std::vector<double> sum(regions, 0.0), cnt(regions, 0.0);
  for (std::size_t v = 0; v < n; ++v) {
    sum[region[v]] += z[static_cast<Eigen::Index>(v)];
    cnt[region[v]] += 1;
  }
  float lo = std::numeric_limits<float>::max();
  for (std::size_t k = 0; k < N; ++k) {
    if (!mask[k]) continue;
    const std::size_t v = id[k];
    out[k] = static_cast<float>(
        (z[static_cast<Eigen::Index>(v)] - sum[region[v]] / cnt[region[v]]) * pitch);
    lo = std::min(lo, out[k]);
  }
  for (std::size_t k = 0; k < N; ++k)
    if (!mask[k]) out[k] = lo;
  return out;
}

}  // namespace hapticlab::modeling
