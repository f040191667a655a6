// Heights from normals: each integrator against analytic height fields (their exact normals,
// so any error is the integrator's), the Frankot-Chellappa wrap-around that the Poisson solve
// avoids, and the masked solve on disconnected regions with garbage outside.

#include "hapticlab/modeling/normal_integration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hapticlab/core/rng.hpp"
#include "photometric_scenes.hpp"

namespace hapticlab::modeling::normal_integration_test {
namespace {

using namespace scenes;  // NOLINT(google-build-using-namespace): the shared test scenes

// RMS of (a - mean a) - (b - mean b) over the pixels where `inside` is non-zero (all when
// empty), divided by the range of b.
double RelativeRms(const std::vector<float>& a, const std::vector<double>& b,
                   const std::vector<std::uint8_t>& inside = {}) {
  double ma = 0, mb = 0, c = 0, lo = 1e300, hi = -1e300;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (inside.empty() || inside[k]) {
      ma += a[k];
      mb += b[k];
      c += 1;
      lo = std::min(lo, b[k]);
      hi = std::max(hi, b[k]);
    }
  double se = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (inside.empty() || inside[k]) se += std::pow((a[k] - ma / c) - (b[k] - mb / c), 2);
  return std::sqrt(se / c) / (hi - lo);
}

TEST(NormalIntegration, EachIntegratorRecoversAPeriodicSurfaceFromItsNormals) {
  // 3 x 2 periods over the image, 25 µm: periodic, so every method's boundary condition
  // holds; heights in metres through the pitch.
  const double A = 25e-6;
  const auto f = Sinusoid(A, kN * kPitch / 3, kN * kPitch / 2);
  const std::vector<std::uint8_t> all(f.n.size(), 1);
  const double fc = RelativeRms(IntegrateNormals(f.n, kN, kN, kPitch), f.h),
               dct = RelativeRms(IntegrateNormalsPoisson(f.n, kN, kN, kPitch), f.h),
               sparse = RelativeRms(IntegrateNormalsMasked(f.n, all, kN, kN, kPitch), f.h);
  std::printf("periodic: height RMS / range %.4f (FC), %.4f (DCT), %.4f (masked)\n", fc, dct,
              sparse);
  EXPECT_LT(fc, 0.01);
  EXPECT_LT(dct, 0.02);
  EXPECT_LT(sparse, 0.02);
  // The sign and the scale: the highest recovered pixel is a crest of the truth, and the
  // recovered peak-to-valley is the true 2 A.
  const auto h = IntegrateNormalsPoisson(f.n, kN, kN, kPitch);
  const auto top = static_cast<std::size_t>(std::max_element(h.begin(), h.end()) - h.begin());
  EXPECT_GT(f.h[top], 0.9 * A);
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  EXPECT_NEAR(*hi - *lo, 2 * A, 0.05 * 2 * A);
}

TEST(NormalIntegration, APlaneIsRecoveredByPoissonButWrappedByFrankotChellappa) {
  // h = s x: not periodic. The DCT and masked solves are exact up to a constant; the FFT's
  // periodic boundary bends the ramp into a sawtooth-like error.
  const double s = 0.05;
  const auto f = Make([&](double x, double) { return s * x; },
                      [&](double, double) { return Eigen::Vector2d(s, 0); });
  const std::vector<std::uint8_t> all(f.n.size(), 1);
  const double fc = RelativeRms(IntegrateNormals(f.n, kN, kN, kPitch), f.h),
               dct = RelativeRms(IntegrateNormalsPoisson(f.n, kN, kN, kPitch), f.h),
               sparse = RelativeRms(IntegrateNormalsMasked(f.n, all, kN, kN, kPitch), f.h);
  EXPECT_LT(dct, 1e-4);
  EXPECT_LT(sparse, 1e-4);
  EXPECT_GT(fc, 0.1);
}

TEST(Photometric, PoissonIntegrationHandlesANonPeriodicTilt) {
  // A tilted plane plus a bump: not periodic, so Frankot-Chellappa's wrap-around distorts it
  // while the Neumann Poisson solve does not.
  const double s = 0.05, A = 10e-6, l = kN * kPitch / 2;
  const auto f = Make([&](double x, double y) { return s * x + A * std::sin(2 * kPi * y / l); },
                      [&](double, double y) {
                        return Eigen::Vector2d(s, A * 2 * kPi / l * std::cos(2 * kPi * y / l));
                      });
  const auto L = DomePreset();
  const auto imgs = Render(f, L, 0.01, 9);
  const auto poisson = Compare(
      f, PhotometricStereo(imgs, L, {.pitch_m = kPitch, .integration = Integration::kPoisson}));
  const auto fc = Compare(f, PhotometricStereo(imgs, L, {.pitch_m = kPitch}));
  std::printf("tilt: Poisson height RMS %.2f %%, Frankot-Chellappa %.2f %%\n",
              100 * poisson.height_rms_fraction, 100 * fc.height_rms_fraction);
  EXPECT_LT(poisson.height_rms_fraction, 0.05);
  EXPECT_GT(fc.height_rms_fraction, poisson.height_rms_fraction);
}

TEST(Photometric, MaskedPoissonIntegration) {
  // h = tilt + bump on a 60 x 44 grid (pixel units): analytic normals.
  const int w = 60, h = 44;
  auto height = [](double x, double y) {
    return 0.3 * x - 0.1 * y + 6 * std::exp(-((x - 25) * (x - 25) + (y - 20) * (y - 20)) / 60);
  };
  auto grad = [](double x, double y) {
    const double g = 6 * std::exp(-((x - 25) * (x - 25) + (y - 20) * (y - 20)) / 60);
    return Eigen::Vector2d(0.3 - g * 2 * (x - 25) / 60, -0.1 - g * 2 * (y - 20) / 60);
  };
  std::vector<Eigen::Vector3f> n;
  std::vector<double> truth;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const auto g = grad(j, i);
      n.push_back(Eigen::Vector3d(-g.x(), -g.y(), 1).normalized().cast<float>());
      truth.push_back(height(j, i));
    }
  // (a) A full mask is the DCT solve's problem exactly.
  const std::vector<std::uint8_t> full(n.size(), 1);
  const auto a = IntegrateNormalsMasked(n, full, w, h, 1.0),
             b = IntegrateNormalsPoisson(n, w, h, 1.0);
  double worst = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    worst = std::max(worst, static_cast<double>(std::abs(a[k] - b[k])));
  EXPECT_LT(worst, 1e-4);
  // (b) Two regions: a disk with a hole and a separate square; outside, the normals are
  // garbage (as a solved background would be).
  std::vector<std::uint8_t> mask(n.size(), 0), region(n.size(), 0);
  Rng rng(3);
  auto noisy = n;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const std::size_t k = static_cast<std::size_t>(i * w + j);
      const double r2 = (j - 22.0) * (j - 22.0) + (i - 21.0) * (i - 21.0);
      if (r2 < 19.0 * 19.0 && r2 > 5.0 * 5.0) mask[k] = region[k] = 1;
      if (j >= 47 && j < 57 && i >= 5 && i < 35) {
        mask[k] = 1;
        region[k] = 2;
      }
      if (!mask[k])
        noisy[k] =
            Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-1, 1), 1).normalized().cast<float>();
    }
  const auto masked = IntegrateNormalsMasked(noisy, mask, w, h, 1.0);
  const auto whole = IntegrateNormalsPoisson(noisy, w, h, 1.0);
  auto rms_in_region = [&](const std::vector<float>& z, int reg, double* mean_out) {
    double mz = 0, mt = 0, c = 0;
    for (std::size_t k = 0; k < z.size(); ++k)
      if (region[k] == reg) {
        mz += z[k];
        mt += truth[k];
        c += 1;
      }
    double se = 0;
    for (std::size_t k = 0; k < z.size(); ++k)
      if (region[k] == reg) se += std::pow((z[k] - mz / c) - (truth[k] - mt / c), 2);
    if (mean_out) *mean_out = mz / c;
    return std::sqrt(se / c);
  };
  double mean1 = 0, mean2 = 0;
  const double e1 = rms_in_region(masked, 1, &mean1), e2 = rms_in_region(masked, 2, &mean2);
  const double e_whole = rms_in_region(whole, 1, nullptr);
  std::printf(
      "masked Poisson: RMS %.4f and %.4f px in the two regions (range ~24 px); whole-image DCT "
      "%.3f px\n",
      e1, e2, e_whole);
  EXPECT_LT(e1, 0.05);
  EXPECT_LT(e2, 0.05);
  EXPECT_GT(e_whole, 10 * e1);
  EXPECT_NEAR(mean1, 0, 1e-3);
  EXPECT_NEAR(mean2, 0, 1e-3);
  const float lo = *std::min_element(masked.begin(), masked.end());
  for (std::size_t k = 0; k < mask.size(); ++k)
    if (!mask[k]) {
      ASSERT_EQ(masked[k], lo);
    }
}

}  // namespace
}  // namespace hapticlab::modeling::normal_integration_test
