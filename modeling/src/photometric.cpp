#include "hapticlab/modeling/photometric.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
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

// One solve's state: the inside pixels' flat-field-corrected readings (pixel-major: pixel k's
// reading under light j at k * m + j), each pixel's b = albedo * normal, the lights it uses and
// whether it solved, the lights' scaled directions and the residual rule's parameters.
struct PixelSolve {
  std::size_t m = 0, nin = 0;
  std::vector<std::size_t> inside;  // image index of each inside pixel
  std::vector<float> inten;
  std::vector<Eigen::Vector3d> b;
  std::vector<std::uint8_t> use, solved;
  std::vector<Eigen::Vector3d> L;  // light_scale[j] * direction of light j
  RobustParams rp;
  std::size_t stride = 1;  // residuals are sampled on at most ~100k pixels for the robust SD
};

// The inside pixels' readings, divided by the reference's where one is given (0 where it is
// dark).
void GatherReadings(const ImageStack& st, const ImageStack* ref,
                    const std::vector<std::uint8_t>& mask, PixelSolve* s) {
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) s->inside.push_back(i);
  s->nin = s->inside.size();
  s->inten.assign(s->nin * s->m, 0.f);
  for (std::size_t j = 0; j < s->m; ++j)
    for (std::size_t k = 0; k < s->nin; ++k) {
      const std::size_t i = s->inside[k];
      float v = st.images[j][i];
      if (ref) v = ref->images[j][i] > 1e-6f ? v / ref->images[j][i] : 0.f;
      s->inten[k * s->m + j] = v;
    }
}

// The lights each pixel starts with (and the whole of the brightest rule): lights darker than
// shadow_fraction of the pixel's brightest reading are out; the brightest rule also drops its
// brightest few.
void StartingLights(const PhotometricOptions& o, PixelSolve* s) {
  const std::size_t m = s->m;
  s->use.assign(s->nin * m, 0);
  for (std::size_t k = 0; k < s->nin; ++k) {
    const float* I = &s->inten[k * m];
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
    for (std::size_t q = 0; q + drop < idx.size(); ++q) s->use[k * m + idx[q]] = 1;
  }
}

// The residual rule's first scale: plain least squares on the starting lights (an overestimate
// when highlights are common; each alternation re-estimates it), at least the noise floor.
double InitialResidualSd(const PixelSolve& s, double noise_floor) {
  const std::size_t m = s.m;
  std::vector<float> sample;
  for (std::size_t k = 0; k < s.nin; k += s.stride) {
    Eigen::Matrix3d Ainv;
    Eigen::Vector3d bb;
    if (!SolvePixel(&s.inten[k * m], &s.use[k * m], s.L, &bb, &Ainv) || !(bb.norm() > 0)) continue;
    for (std::size_t j = 0; j < m; ++j)
      if (s.use[k * m + j])
        sample.push_back(
            static_cast<float>(std::abs(static_cast<double>(s.inten[k * m + j]) - s.L[j].dot(bb)) /
                               (s.L[j].norm() * bb.norm()) /
                               std::sqrt(std::max(1 - s.L[j].dot(Ainv * s.L[j]), 1e-3))));
  }
  return std::max(RobustSd(sample), noise_floor);
}

// One pass over every `step`-th pixel: the robust (or fixed-set) fit with the current light
// scales, then the robust SD re-estimated from the kept residuals. Progress from p0 to p1.
void PixelPass(const PhotometricOptions& o, std::size_t step, double p0, double p1,
               const std::function<void(double)>& progress, PixelSolve* s) {
  const std::size_t m = s->m;
  std::vector<float> sample;
  std::vector<double> t(m);
  const std::size_t every = std::max<std::size_t>(1, s->stride / step);
  for (std::size_t k = 0; k < s->nin; k += step) {
    if (o.rejection == Rejection::kResidual) {
      s->solved[k] =
          RobustPixel(&s->inten[k * m], &s->use[k * m], s->L, s->rp, &s->b[k], t.data()) ? 1 : 0;
      if (s->solved[k] && (k / step) % every == 0)
        for (std::size_t j = 0; j < m; ++j)
          if (s->use[k * m + j]) sample.push_back(static_cast<float>(std::abs(t[j])));
    } else {
      Eigen::Matrix3d Ainv;
      s->solved[k] = SolvePixel(&s->inten[k * m], &s->use[k * m], s->L, &s->b[k], &Ainv) ? 1 : 0;
      if (!s->solved[k]) s->b[k].setZero();
    }
    if (progress && k % 65536 == 0)
      progress(p0 + (p1 - p0) * static_cast<double>(k) / static_cast<double>(s->nin));
  }
  if (o.rejection == Rejection::kResidual && !sample.empty())
    s->rp.sigma = std::max(RobustSd(sample), o.noise_floor);
}

// Per light: s_j = argmin sum_i (I_ij - s_j l_j . b_i)^2 over every `step`-th pixel using it,
// with a weak prior towards the mean (weight kScalePrior of the data: where the data cannot
// tell a light's intensity from the normals, a nearly flat sample, it stays); not yet
// normalized to mean 1.
std::vector<double> LightScales(const PixelSolve& s, const std::vector<Light>& lights,
                                std::size_t step) {
  constexpr double kScalePrior = 1e-3;
  const std::size_t m = s.m;
  std::vector<double> s_new(m, 1.0);
  for (std::size_t j = 0; j < m; ++j) {
    double num = 0, den = 0;
    for (std::size_t k = 0; k < s.nin; k += step) {
      if (!s.use[k * m + j] || !s.solved[k]) continue;
      const double pred = lights[j].direction.dot(s.b[k]);
      num += pred * s.inten[k * m + j];
      den += pred * pred;
    }
    s_new[j] = den > 0 ? (num + kScalePrior * den) / (den * (1 + kScalePrior)) : 1.0;
  }
  return s_new;
}

// Alternations between the pixels and the light scales (mean 1) into r->light_scale, on a
// subsample of at most kAlsPixels pixels (the m light scales need far fewer readings than
// there are), until no scale changes by more than kAlsTolerance or o.iterations are run.
void AlternateLightScales(const std::vector<Light>& lights, const PhotometricOptions& o,
                          const std::function<void(double)>& progress, PixelSolve* s,
                          PhotometricResult* r) {
  constexpr std::size_t kAlsPixels = 1000;
  constexpr double kAlsTolerance = 1e-6;
  const std::size_t m = s->m, als_step = std::max<std::size_t>(1, s->nin / kAlsPixels);
  r->alternations = 0;
  for (int it = 0; it < o.iterations; ++it) {
    PixelPass(o, als_step, 0, 0, progress, s);
    const std::vector<double> s_new = LightScales(*s, lights, als_step);
    double mean = 0;
    for (std::size_t j = 0; j < m; ++j) mean += s_new[j];
    mean /= static_cast<double>(m);
    double change = 0;
    for (std::size_t j = 0; j < m; ++j) {
      change = std::max(change, std::abs(s_new[j] / mean - r->light_scale[j]));
      r->light_scale[j] = s_new[j] / mean;
    }
    for (std::size_t j = 0; j < m; ++j) s->L[j] = r->light_scale[j] * lights[j].direction;
    ++r->alternations;
    if (progress) progress(0.5 * (it + 1.0) / o.iterations);
    if (change < kAlsTolerance) break;
  }
}

// The solved pixels' albedo and normals (+z where unsolved) into r, with each light's share of
// the pixels that used it and the readings dropped as too bright or too dark.
void CollectPixels(const PixelSolve& s, double shadow_fraction, PhotometricResult* r) {
  const std::size_t m = s.m;
  std::size_t bright = 0, dark = 0;
  for (std::size_t k = 0; k < s.nin; ++k) {
    const std::size_t i = s.inside[k];
    const Eigen::Vector3d& b = s.b[k];
    const double a = b.norm();
    if (!s.solved[k] || !(a > 0) || !(b.z() > 0)) {
      ++r->unsolved_pixels;
      r->normals[i] = Eigen::Vector3f::UnitZ();
      continue;
    }
    r->albedo[i] = static_cast<float>(a);
    r->normals[i] = (b / a).cast<float>();
    for (std::size_t j = 0; j < m; ++j) {
      const auto reading = static_cast<double>(s.inten[k * m + j]);
      if (s.use[k * m + j]) {
        r->light_use[j] += 1;
      } else if (reading > s.L[j].dot(b) && reading >= shadow_fraction * s.L[j].norm() * a) {
        ++bright;
      } else {
        ++dark;
      }
    }
  }
  for (auto& u : r->light_use) u /= std::max<double>(1, static_cast<double>(s.nin));
  const double readings =
      std::max<double>(1, static_cast<double>(s.nin - r->unsolved_pixels) * static_cast<double>(m));
  r->dropped_bright = static_cast<double>(bright) / readings;
  r->dropped_dark = static_cast<double>(dark) / readings;
}

// The integrability check of the normals' frame and their integration into r->height_m (the
// masked solve where the mask is irregular).
void CheckAndIntegrate(const PhotometricOptions& o, bool irregular, PhotometricResult* r) {
  const auto [given, mirrored] = CurlMedians(r->normals, r->mask, r->width, r->height);
  r->mirrored_curl_ratio = mirrored > 0 ? given / mirrored : 1.0;
  r->axis_flip_suspected = r->mirrored_curl_ratio > kAxisFlipRatio;
  if (!irregular) {
    r->height_m = o.integration == Integration::kPoisson
                      ? IntegrateNormalsPoisson(r->normals, r->width, r->height, o.pitch_m)
                      : IntegrateNormals(r->normals, r->width, r->height, o.pitch_m);
  } else {
    r->height_m = IntegrateNormalsMasked(r->normals, r->mask, r->width, r->height, o.pitch_m);
  }
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

  PixelSolve s;
  s.m = m;
  GatherReadings(st, ref, r.mask, &s);
  s.b.assign(s.nin, Eigen::Vector3d::Zero());
  s.solved.assign(s.nin, 0);
  StartingLights(o, &s);
  s.L.resize(m);
  for (std::size_t j = 0; j < m; ++j) s.L[j] = r.light_scale[j] * lights[j].direction;
  s.stride = std::max<std::size_t>(1, s.nin / 100000);
  s.rp = {.sigma = 0,
          .threshold = o.outlier_sigmas,
          .shadow_fraction = o.shadow_fraction,
          .min_lights = std::max(3, o.min_lights)};
  if (o.rejection == Rejection::kResidual) s.rp.sigma = InitialResidualSd(s, o.noise_floor);
  AlternateLightScales(lights, o, progress, &s, &r);
  PixelPass(o, 1, 0.5, 0.95, progress, &s);  // every pixel with the final light scales
  r.residual_sd = s.rp.sigma;
  CollectPixels(s, o.shadow_fraction, &r);
  CheckAndIntegrate(o, irregular, &r);
  if (progress) progress(1.0);
  return r;
}

}  // namespace hapticlab::modeling
