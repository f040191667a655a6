// Photometric stereo on images rendered here from known height fields under the dome. (The
// lights and image files: photometric_io_test.cpp; the command line:
// tests/apps/cmd_model_photometric_test.cpp.)

#include "hapticlab/modeling/photometric.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "photometric_scenes.hpp"

namespace hapticlab::modeling::photometric_test {
namespace {

using namespace scenes;  // NOLINT(google-build-using-namespace): the shared test scenes

TEST(Photometric, DomePresetHasThirtyLightsAtThreeElevations) {
  const auto d = DomePreset();
  ASSERT_EQ(d.size(), 30u);
  EXPECT_NEAR(std::asin(d[0].direction.z()) * 180 / kPi, 40, 1e-9);
  EXPECT_NEAR(std::asin(d[29].direction.z()) * 180 / kPi, 70, 1e-9);
}

TEST(Photometric, SinusoidRecoveredAtOnePercentNoise) {
  // Periodic over the image (the Frankot-Chellappa assumption): 4 x 3 periods, 30 µm.
  const double A = 30e-6, lx = kN * kPitch / 4, ly = kN * kPitch / 3;
  const auto f = Sinusoid(A, lx, ly);
  const auto L = DomePreset();
  const auto r = PhotometricStereo(Render(f, L, 0.01, 1), L, {.pitch_m = kPitch});
  const auto e = Compare(f, r);
  std::printf("sinusoid: mean normal error %.3f deg, height RMS %.2f %% of range\n",
              e.mean_angle_deg, 100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, RoughSurfaceAndThreeShadowedLights) {
  Rng rng(5);
  std::vector<std::array<double, 4>> waves;
  for (int k = 0; k < 12; ++k)
    waves.push_back({5e-6 * rng.Uniform(0.5, 1),
                     2 * kPi * static_cast<double>(1 + rng.Below(6)) / (kN * kPitch),
                     2 * kPi * static_cast<double>(1 + rng.Below(6)) / (kN * kPitch),
                     rng.Uniform(0, 2 * kPi)});
  const auto f = Make(
      [&](double x, double y) {
        double s = 0;
        for (const auto& w : waves) s += w[0] * std::sin(w[1] * x + w[2] * y + w[3]);
        return s;
      },
      [&](double x, double y) {
        Eigen::Vector2d g(0, 0);
        for (const auto& w : waves)
          g += w[0] * std::cos(w[1] * x + w[2] * y + w[3]) * Eigen::Vector2d(w[1], w[2]);
        return g;
      });
  const auto L = DomePreset();
  const auto e = Compare(f, PhotometricStereo(Render(f, L, 0.01, 2, 3), L, {.pitch_m = kPitch}));
  std::printf("rough, 3 shadowed lights: mean normal error %.3f deg, height RMS %.2f %%\n",
              e.mean_angle_deg, 100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, PlateauWithSmoothStepsRecovered) {
  // A raised plateau (steps up and down, 40 µm, edges 4 pixels wide): periodic, integrable.
  const double H = 40e-6, w = 4 * kPitch, a = kN * kPitch * 0.3, b = kN * kPitch * 0.7;
  auto step = [&](double x) { return 0.5 * (std::tanh((x - a) / w) - std::tanh((x - b) / w)); };
  auto dstep = [&](double x) {
    return 0.5 / w *
           (1 / std::pow(std::cosh((x - a) / w), 2) - 1 / std::pow(std::cosh((x - b) / w), 2));
  };
  const auto f = Make([&](double x, double) { return H * step(x); },
                      [&](double x, double) { return Eigen::Vector2d(H * dstep(x), 0); });
  const auto L = DomePreset();
  const auto e = Compare(f, PhotometricStereo(Render(f, L, 0.01, 4), L, {.pitch_m = kPitch}));
  std::printf("plateau: mean normal error %.3f deg, height RMS %.2f %%\n", e.mean_angle_deg,
              100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, SphereNormalsAreExact) {
  // A spherical cap: the classic case with known normals (height not periodic: normals only).
  const double R = kN * kPitch * 0.6, c = kN * kPitch / 2;
  const auto f = Make(
      [&](double x, double y) {
        return std::sqrt(std::max(R * R - (x - c) * (x - c) - (y - c) * (y - c), 0.0));
      },
      [&](double x, double y) {
        const double z = std::sqrt(std::max(R * R - (x - c) * (x - c) - (y - c) * (y - c), 1e-30));
        return Eigen::Vector2d(-(x - c) / z, -(y - c) / z);
      });
  const auto L = DomePreset();
  const auto r = PhotometricStereo(Render(f, L, 0.0, 3), L, {.pitch_m = kPitch});
  double worst = 0;
  for (int i = kN / 4; i < 3 * kN / 4; ++i)
    for (int j = kN / 4; j < 3 * kN / 4; ++j) {
      const std::size_t k = static_cast<std::size_t>(i * kN + j);
      worst = std::max(
          worst, std::acos(std::clamp(static_cast<double>(f.n[k].dot(r.normals[k])), -1.0, 1.0)) *
                     180 / kPi);
    }
  EXPECT_LT(worst, 0.5);
}

// ---------------------------------------------------------------------------------------
// Real-capture conditions: specular highlights, attached shadows, masks, frames, formats.

TEST(Photometric, ResidualRejectionHandlesHighlightsShadowsAndMask) {
  // 96 x 96, sphere of radius 40 px, masked to 0.9 R (slopes up to 64°): every light lights
  // a highlight somewhere and leaves the far side in attached shadow.
  const auto s = MakeSphere(96, 40, 0.9);
  const auto L = TwelveLights();
  PhotometricOptions o{.pitch_m = kPitch, .integration = Integration::kPoisson};
  o.mask = s.mask;
  const auto plain = RenderSphere(s, L, 0.0, 0.0, 11);
  const auto shiny = RenderSphere(s, L, 0.6, 40.0, 11);  // the same noise
  const auto noise_only = PhotometricStereo(plain, L, o);
  const auto adaptive = PhotometricStereo(shiny, L, o);
  auto fixed_rule = o;
  fixed_rule.rejection = Rejection::kBrightest;
  const auto brightest = PhotometricStereo(shiny, L, fixed_rule);
  const double e0 = MedianErrorDeg(s, noise_only.normals), e1 = MedianErrorDeg(s, adaptive.normals),
               e2 = MedianErrorDeg(s, brightest.normals);
  std::printf(
      "sphere, 12 lights: median normal error %.3f deg noise only, %.3f deg with highlights "
      "(residual rule), "
      "%.3f deg (brightest rule); dropped %.1f %% bright, %.1f %% dark; residual SD %.4f\n",
      e0, e1, e2, 100 * adaptive.dropped_bright, 100 * adaptive.dropped_dark, adaptive.residual_sd);
  EXPECT_LT(e1, e0 + 0.5);
  EXPECT_LT(e1, e2);
  EXPECT_GT(adaptive.dropped_bright, 0.0);  // highlights were found ...
  EXPECT_LT(noise_only.dropped_bright,
            0.02);  // ... and few lights are dropped where there are none
  // Outside the mask nothing is solved.
  for (std::size_t i = 0; i < s.mask.size(); ++i)
    if (!s.mask[i]) {
      ASSERT_EQ(adaptive.normals[i], Eigen::Vector3f::Zero());
    }
  // The height of the cap inside the mask (Poisson, Neumann on the mask boundary), as a
  // fraction of its range: asserted for the noise-only images; with highlights it is printed
  // (the pixels near the top, where most lights carry a highlight, are the least accurate).
  auto height_rms = [&](const PhotometricResult& r) {
    double mt = 0, me = 0, cnt = 0, lo = 1e300, hi = -1e300;
    for (std::size_t i = 0; i < s.mask.size(); ++i)
      if (s.mask[i]) {
        mt += s.height[i] * kPitch;
        me += r.height_m[i];
        cnt += 1;
        lo = std::min(lo, s.height[i] * kPitch);
        hi = std::max(hi, s.height[i] * kPitch);
      }
    double se = 0;
    for (std::size_t i = 0; i < s.mask.size(); ++i)
      if (s.mask[i])
        se += std::pow((r.height_m[i] - me / cnt) - (s.height[i] * kPitch - mt / cnt), 2);
    return std::sqrt(se / cnt) / (hi - lo);
  };
  const double h0 = height_rms(noise_only), h1 = height_rms(adaptive);
  std::printf(
      "sphere cap inside the mask: height RMS %.2f %% of the range noise only, %.2f %% with "
      "highlights\n",
      100 * h0, 100 * h1);
  EXPECT_LT(h0, 0.005);
}

TEST(Photometric, MirroredLightFrameIsReported) {
  const auto s = MakeSphere(64, 28, 0.9);
  const auto L = TwelveLights();
  const auto img = RenderSphere(s, L, 0.0, 0.0, 5);
  PhotometricOptions o{.pitch_m = kPitch, .integration = Integration::kPoisson};
  o.mask = s.mask;
  const auto right = PhotometricStereo(img, L, o);
  auto mirrored_y = L, mirrored_x = L;
  for (auto& l : mirrored_y) l.direction.y() = -l.direction.y();
  for (auto& l : mirrored_x) l.direction.x() = -l.direction.x();
  const auto wrong_y = PhotometricStereo(img, mirrored_y, o),
             wrong_x = PhotometricStereo(img, mirrored_x, o);
  std::printf("curl ratio: %.2f right, %.2f y mirrored, %.2f x mirrored\n",
              right.mirrored_curl_ratio, wrong_y.mirrored_curl_ratio, wrong_x.mirrored_curl_ratio);
  EXPECT_FALSE(right.axis_flip_suspected);
  EXPECT_TRUE(wrong_y.axis_flip_suspected);
  EXPECT_TRUE(wrong_x.axis_flip_suspected);
  // A mirrored frame fits every pixel equally well (the error is the mirror, not noise).
  EXPECT_LT(MedianErrorDeg(s, right.normals), 1.0);
  EXPECT_GT(MedianErrorDeg(s, wrong_y.normals), 5.0);
}

}  // namespace
}  // namespace hapticlab::modeling::photometric_test
