#include "hapticlab/modeling/photometric.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {
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
    throw InputError(
        "", 0, "integration",
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

}  // namespace hapticlab::modeling
