#include "hapticlab/modeling/photometric.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;

}  // namespace

namespace {

// Per pixel: b = argmin sum over used lights of (I_j - L_j . b)^2, with A^-1 for leverages.
bool SolvePixel(const float* I, const std::uint8_t* use, const std::vector<Eigen::Vector3d>& L,
                Eigen::Vector3d* b, Eigen::Matrix3d* Ainv) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t j = 0; j < L.size(); ++j) {
    if (!use[j]) continue;
    A.noalias() += L[j] * L[j].transpose();
    y += L[j] * static_cast<double>(I[j]);
    ++count;
  }
  const double tr = A.trace() / 3;
  if (count < 3 || !(std::abs(A.determinant()) > 1e-9 * tr * tr * tr)) return false;
  *Ainv = A.inverse();
  *b = *Ainv * y;
  return true;
}

struct RobustParams {
  double sigma = 0.01, threshold = 3, shadow_fraction = 0.05;
  int min_lights = 4;
};

// The residual rule for one pixel: starts from the lights in `use` and updates them in place.
// Returns false when fewer than 3 usable lights remain (b = 0).
bool RobustPixel(const float* I, std::uint8_t* use, const std::vector<Eigen::Vector3d>& L,
                 const RobustParams& p, Eigen::Vector3d* b, double* t_out) {
  const std::size_t m = L.size();
  Eigen::Matrix3d Ainv;
  const double thr = p.threshold * p.sigma;
  for (std::size_t pass = 0; pass < 2 * m + 2; ++pass) {
    if (!SolvePixel(I, use, L, b, &Ainv) || !(b->norm() > 0)) {
      b->setZero();
      return false;
    }
    const double bn = b->norm();
    int count = 0, worst_hi = -1, worst_lo = -1, dark_in = 0, back = 0;
    double hi_t = thr, lo_t = -thr;
    for (std::size_t j = 0; j < m; ++j) {
      const double d = L[j].norm() * bn;  // the pixel's brightness under light j, facing it
      const double e = (static_cast<double>(I[j]) - L[j].dot(*b)) / d;
      const double h = L[j].dot(Ainv * L[j]);
      const bool dark = static_cast<double>(I[j]) < p.shadow_fraction * d;
      double t;
      if (use[j]) {
        ++count;
        t = e / std::sqrt(std::max(1 - h, 1e-3));
        if (dark) {
          ++dark_in;
        } else if (t > hi_t) {
          hi_t = t;
          worst_hi = static_cast<int>(j);
        } else if (t < lo_t) {
          lo_t = t;
          worst_lo = static_cast<int>(j);
        }
      } else {
        t = e / std::sqrt(1 + h);
        if (!dark && std::abs(t) <= thr) ++back;
      }
      t_out[j] = dark ? -1e30 : t;
    }
    if (dark_in > 0) {
      for (std::size_t j = 0; j < m; ++j)
        if (use[j] && t_out[j] == -1e30) use[j] = 0;
    } else if ((worst_hi >= 0 || worst_lo >= 0) && count > p.min_lights) {
      // Too bright first: a highlight left in drags the fit up, so that good readings look
      // too dark; what is too dark once the highlights are out is a partial shadow.
      use[worst_hi >= 0 ? worst_hi : worst_lo] = 0;
    } else if (back > 0) {
      for (std::size_t j = 0; j < m; ++j)
        if (!use[j] && t_out[j] != -1e30 && std::abs(t_out[j]) <= thr) use[j] = 1;
    } else {
      return true;
    }
  }
  return SolvePixel(I, use, L, b, &Ainv);
}

// Robust SD (1.4826 x median absolute value) of a sample.
double RobustSd(std::vector<float>& v) {
  if (v.empty()) return 0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return 1.4826 * static_cast<double>(*mid);
}

// Median |curl| of the normals' gradient field over 2x2 cells inside the mask, as given and
// with the y component mirrored (medians: a few badly solved pixels do not decide); cells
// with a steep normal (n_z < 0.3) are skipped.
std::pair<double, double> CurlMedians(const std::vector<Eigen::Vector3f>& n,
                                      const std::vector<std::uint8_t>& mask, int w, int h) {
  std::vector<float> given, mirrored;
  const auto W = static_cast<std::size_t>(w);
  auto grad = [&](std::size_t k) {
    return Eigen::Vector2d(-static_cast<double>(n[k].x()) / static_cast<double>(n[k].z()),
                           -static_cast<double>(n[k].y()) / static_cast<double>(n[k].z()));
  };
  for (std::size_t i = 0; i + 1 < static_cast<std::size_t>(h); ++i)
    for (std::size_t j = 0; j + 1 < W; ++j) {
      const std::size_t k[4] = {i * W + j, i * W + j + 1, (i + 1) * W + j, (i + 1) * W + j + 1};
      bool ok = true;
      for (auto c : k) ok = ok && mask[c] && n[c].z() >= 0.3f;
      if (!ok) continue;
      const auto g00 = grad(k[0]), g01 = grad(k[1]), g10 = grad(k[2]), g11 = grad(k[3]);
      const double qx = 0.5 * (g01.y() + g11.y() - g00.y() - g10.y());
      const double py = 0.5 * (g10.x() + g11.x() - g00.x() - g01.x());
      given.push_back(static_cast<float>(std::abs(qx - py)));
      mirrored.push_back(static_cast<float>(std::abs(qx + py)));
    }
  // RobustSd is 1.4826 x the median; the factor cancels in the ratio.
  return {RobustSd(given), RobustSd(mirrored)};
}

}  // namespace

PhotometricResult PhotometricStereo(const ImageStack& st, const std::vector<Light>& lights,
                                    const PhotometricOptions& o, const ImageStack* ref,
                                    const std::function<void(double)>& progress) {
  const std::size_t m = lights.size(),
                    npx = static_cast<std::size_t>(st.width) * static_cast<std::size_t>(st.height);
  HL_REQUIRE(st.images.size() == m, "one image per light is needed");
  HL_REQUIRE(m >= 3, "photometric stereo needs at least 3 lights");
  HL_REQUIRE(!ref || ref->images.size() == m, "one reference image per light is needed");
  HL_REQUIRE(o.mask.empty() || o.mask.size() == npx, "the mask must have width x height values");
  PhotometricResult r;
  r.width = st.width;
  r.height = st.height;
  r.mask.assign(npx, 1);
  if (!o.mask.empty())
    for (std::size_t i = 0; i < npx; ++i) r.mask[i] = o.mask[i] ? 1 : 0;
  const bool irregular = std::find(r.mask.begin(), r.mask.end(), 0) != r.mask.end();
  if (irregular && o.integration == Integration::kFrankotChellappa)
    throw std::invalid_argument(
        "Frankot-Chellappa integrates the whole image; a mask needs the Poisson solve");
  r.albedo.assign(npx, 0.f);
  r.normals.assign(npx, Eigen::Vector3f::Zero());
  r.light_scale.assign(m, 1.0);
  r.light_use.assign(m, 0.0);
  std::vector<std::size_t> inside;
  for (std::size_t i = 0; i < npx; ++i)
    if (r.mask[i]) inside.push_back(i);
  const std::size_t nin = inside.size();
  std::vector<float> inten(nin * m);  // pixel-major copy of the inside pixels, flat-field corrected
  for (std::size_t j = 0; j < m; ++j)
    for (std::size_t k = 0; k < nin; ++k) {
      const std::size_t i = inside[k];
      float v = st.images[j][i];
      if (ref) v = ref->images[j][i] > 1e-6f ? v / ref->images[j][i] : 0.f;
      inten[k * m + j] = v;
    }
  std::vector<Eigen::Vector3d> b(nin, Eigen::Vector3d::Zero());
  std::vector<std::uint8_t> use(nin * m, 0), solved(nin, 0);
  // Start (and the whole of the brightest rule): lights darker than shadow_fraction of the
  // pixel's brightest reading are out; the brightest rule also drops its brightest few.
  for (std::size_t k = 0; k < nin; ++k) {
    const float* I = &inten[k * m];
    const float mx = *std::max_element(I, I + m);
    std::vector<std::size_t> idx;
    for (std::size_t j = 0; j < m; ++j)
      if (I[j] > o.shadow_fraction * mx) idx.push_back(j);
    std::size_t drop = 0;
    if (o.rejection == Rejection::kBrightest) {
      std::sort(idx.begin(), idx.end(), [&](auto a, auto c) { return I[a] < I[c]; });
      drop = idx.size() >= 6 ? static_cast<std::size_t>(std::floor(o.specular_fraction *
                                                                   static_cast<double>(idx.size())))
                             : 0;
    }
    for (std::size_t q = 0; q + drop < idx.size(); ++q) use[k * m + idx[q]] = 1;
  }
  std::vector<Eigen::Vector3d> L(m);
  auto set_lights = [&] {
    for (std::size_t j = 0; j < m; ++j) L[j] = r.light_scale[j] * lights[j].direction;
  };
  set_lights();
  // Residuals are sampled on at most ~100k pixels for the robust SD.
  const std::size_t stride = std::max<std::size_t>(1, nin / 100000);
  std::vector<float> sample;
  std::vector<double> t(m);
  RobustParams rp{.sigma = 0,
                  .threshold = o.outlier_sigmas,
                  .shadow_fraction = o.shadow_fraction,
                  .min_lights = std::max(3, o.min_lights)};
  // The residual rule's first scale: plain least squares on the starting lights (an
  // overestimate when highlights are common; each alternation below re-estimates it).
  if (o.rejection == Rejection::kResidual) {
    for (std::size_t k = 0; k < nin; k += stride) {
      Eigen::Matrix3d Ainv;
      Eigen::Vector3d bb;
      if (!SolvePixel(&inten[k * m], &use[k * m], L, &bb, &Ainv) || !(bb.norm() > 0)) continue;
      for (std::size_t j = 0; j < m; ++j)
        if (use[k * m + j])
          sample.push_back(static_cast<float>(
              std::abs(static_cast<double>(inten[k * m + j]) - L[j].dot(bb)) /
              (L[j].norm() * bb.norm()) / std::sqrt(std::max(1 - L[j].dot(Ainv * L[j]), 1e-3))));
    }
    rp.sigma = std::max(RobustSd(sample), o.noise_floor);
  }
  // One pass over every `step`-th pixel: robust (or fixed-set) fit with the current light
  // scales, then the robust SD re-estimated from the kept residuals.
  auto pixel_pass = [&](std::size_t step, double p0, double p1) {
    sample.clear();
    const std::size_t every = std::max<std::size_t>(1, stride / step);
    for (std::size_t k = 0; k < nin; k += step) {
      if (o.rejection == Rejection::kResidual) {
        solved[k] = RobustPixel(&inten[k * m], &use[k * m], L, rp, &b[k], t.data()) ? 1 : 0;
        if (solved[k] && (k / step) % every == 0)
          for (std::size_t j = 0; j < m; ++j)
            if (use[k * m + j]) sample.push_back(static_cast<float>(std::abs(t[j])));
      } else {
        Eigen::Matrix3d Ainv;
        solved[k] = SolvePixel(&inten[k * m], &use[k * m], L, &b[k], &Ainv) ? 1 : 0;
        if (!solved[k]) b[k].setZero();
      }
      if (progress && k % 65536 == 0)
        progress(p0 + (p1 - p0) * static_cast<double>(k) / static_cast<double>(nin));
    }
    if (o.rejection == Rejection::kResidual && !sample.empty())
      rp.sigma = std::max(RobustSd(sample), o.noise_floor);
  };
  // Alternations on a subsample of at most kAlsPixels pixels (the m light scales need far
  // fewer readings than there are), until no scale changes by more than kAlsTolerance.
  constexpr std::size_t kAlsPixels = 1000;
  constexpr double kAlsTolerance = 1e-6;
  constexpr double kScalePrior = 1e-3;
  const std::size_t als_step = std::max<std::size_t>(1, nin / kAlsPixels);
  r.alternations = 0;
  for (int it = 0; it < o.iterations; ++it) {
    pixel_pass(als_step, 0, 0);
    // Per light: s_j = argmin sum_i (I_ij - s_j l_j . b_i)^2 over the pixels using it, mean 1.
    std::vector<double> s_new(m, 1.0);
    double mean = 0;
    for (std::size_t j = 0; j < m; ++j) {
      double num = 0, den = 0;
      for (std::size_t k = 0; k < nin; k += als_step) {
        if (!use[k * m + j] || !solved[k]) continue;
        const double pred = lights[j].direction.dot(b[k]);
        num += pred * inten[k * m + j];
        den += pred * pred;
      }
      // A weak prior towards the mean (weight kScalePrior of the data): where the data
      // cannot tell a light's intensity from the normals (a nearly flat sample), it stays.
      s_new[j] = den > 0 ? (num + kScalePrior * den) / (den * (1 + kScalePrior)) : 1.0;
      mean += s_new[j];
    }
    mean /= static_cast<double>(m);
    double change = 0;
    for (std::size_t j = 0; j < m; ++j) {
      change = std::max(change, std::abs(s_new[j] / mean - r.light_scale[j]));
      r.light_scale[j] = s_new[j] / mean;
    }
    set_lights();
    ++r.alternations;
    if (progress) progress(0.5 * (it + 1.0) / o.iterations);
    if (change < kAlsTolerance) break;
  }
  pixel_pass(1, 0.5, 0.95);  // every pixel with the final light scales
  r.residual_sd = rp.sigma;
  std::size_t bright = 0, dark = 0;
  for (std::size_t k = 0; k < nin; ++k) {
    const std::size_t i = inside[k];
    const double a = b[k].norm();
    if (!solved[k] || !(a > 0) || !(b[k].z() > 0)) {
      ++r.unsolved_pixels;
      r.normals[i] = Eigen::Vector3f::UnitZ();
      continue;
    }
    r.albedo[i] = static_cast<float>(a);
    r.normals[i] = (b[k] / a).cast<float>();
    for (std::size_t j = 0; j < m; ++j) {
      if (use[k * m + j]) {
        r.light_use[j] += 1;
      } else if (static_cast<double>(inten[k * m + j]) > L[j].dot(b[k]) &&
                 static_cast<double>(inten[k * m + j]) >= o.shadow_fraction * L[j].norm() * a) {
        ++bright;
      } else {
        ++dark;
      }
    }
  }
  for (auto& u : r.light_use) u /= std::max<double>(1, static_cast<double>(nin));
  const double readings =
      std::max<double>(1, static_cast<double>(nin - r.unsolved_pixels) * static_cast<double>(m));
  r.dropped_bright = static_cast<double>(bright) / readings;
  r.dropped_dark = static_cast<double>(dark) / readings;
  const auto [given, mirrored] = CurlMedians(r.normals, r.mask, r.width, r.height);
  r.mirrored_curl_ratio = mirrored > 0 ? given / mirrored : 1.0;
  r.axis_flip_suspected = r.mirrored_curl_ratio > kAxisFlipRatio;
  if (!irregular) {
    r.height_m = o.integration == Integration::kPoisson
                     ? IntegrateNormalsPoisson(r.normals, r.width, r.height, o.pitch_m)
                     : IntegrateNormals(r.normals, r.width, r.height, o.pitch_m);
  } else {
    r.height_m = IntegrateNormalsMasked(r.normals, r.mask, r.width, r.height, o.pitch_m);
  }
  if (progress) progress(1.0);
  return r;
}

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
  std::vector<std::size_t> region(n, kOut), stack;
  std::size_t regions = 0;
  for (std::size_t k = 0; k < N; ++k) {
    if (!mask[k] || region[id[k]] != kOut) continue;
    diag[id[k]] += 1;
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
