// Photometric stereo on images rendered here from known height fields under the dome.

#include "hapticlab/modeling/photometric.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <numbers>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kN = 128;             // image size
constexpr double kPitch = 20e-6;    // m per pixel

struct Field {
  std::vector<double> h;            // metres
  std::vector<Eigen::Vector3f> n;   // true normals
};

// Height field with analytic gradient, sampled on the grid.
Field Make(const std::function<double(double, double)>& h, const std::function<Eigen::Vector2d(double, double)>& g) {
  Field f;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const double x = j * kPitch, y = i * kPitch;
      f.h.push_back(h(x, y));
      const auto d = g(x, y);
      f.n.push_back(Eigen::Vector3d(-d.x(), -d.y(), 1).normalized().cast<float>());
    }
  return f;
}

// Lambertian images under the dome, relative noise `noise`, optional shadowed lights.
ImageStack Render(const Field& f, const std::vector<Light>& L, double noise, std::uint64_t seed, int shadowed = 0) {
  Rng rng(seed);
  ImageStack s;
  s.width = s.height = kN;
  for (std::size_t j = 0; j < L.size(); ++j) {
    std::vector<float> img(f.n.size());
    for (std::size_t i = 0; i < img.size(); ++i) {
      const double v = 0.8 * std::max(0.0, L[j].direction.dot(f.n[i].cast<double>()));
      img[i] = static_cast<float>(v * (1 + noise * rng.Normal()));
      // Cast shadows: the first `shadowed` lights are blocked on the left half.
      if (static_cast<int>(j) < shadowed && (i % kN) < kN / 2) img[i] = 0;
    }
    s.images.push_back(img);
  }
  return s;
}

struct Errors {
  double mean_angle_deg, height_rms_fraction;
};

Errors Compare(const Field& f, const PhotometricResult& r) {
  double ang = 0;
  for (std::size_t i = 0; i < f.n.size(); ++i)
    ang += std::acos(std::clamp(static_cast<double>(f.n[i].dot(r.normals[i])), -1.0, 1.0));
  double mt = 0, me = 0, lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < f.h.size(); ++i) {
    mt += f.h[i];
    me += r.height_m[i];
    lo = std::min(lo, f.h[i]);
    hi = std::max(hi, f.h[i]);
  }
  mt /= static_cast<double>(f.h.size());
  me /= static_cast<double>(f.h.size());
  double se = 0;
  for (std::size_t i = 0; i < f.h.size(); ++i) se += std::pow((r.height_m[i] - me) - (f.h[i] - mt), 2);
  return {ang / static_cast<double>(f.n.size()) * 180 / kPi, std::sqrt(se / static_cast<double>(f.h.size())) / (hi - lo)};
}

TEST(Photometric, DomePresetHasThirtyLightsAtThreeElevations) {
  const auto d = DomePreset();
  ASSERT_EQ(d.size(), 30u);
  EXPECT_NEAR(std::asin(d[0].direction.z()) * 180 / kPi, 40, 1e-9);
  EXPECT_NEAR(std::asin(d[29].direction.z()) * 180 / kPi, 70, 1e-9);
}

TEST(Photometric, SinusoidRecoveredAtOnePercentNoise) {
  // Periodic over the image (the Frankot-Chellappa assumption): 4 x 3 periods, 30 µm.
  const double A = 30e-6, lx = kN * kPitch / 4, ly = kN * kPitch / 3;
  const auto f = Make([&](double x, double y) { return A * std::sin(2 * kPi * x / lx) * std::cos(2 * kPi * y / ly); },
                      [&](double x, double y) {
                        return Eigen::Vector2d(A * 2 * kPi / lx * std::cos(2 * kPi * x / lx) * std::cos(2 * kPi * y / ly),
                                               -A * 2 * kPi / ly * std::sin(2 * kPi * x / lx) * std::sin(2 * kPi * y / ly));
                      });
  const auto L = DomePreset();
  const auto r = PhotometricStereo(Render(f, L, 0.01, 1), L, {.pitch_m = kPitch});
  const auto e = Compare(f, r);
  std::printf("sinusoid: mean normal error %.3f deg, height RMS %.2f %% of range\n", e.mean_angle_deg, 100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, RoughSurfaceAndThreeShadowedLights) {
  Rng rng(5);
  std::vector<std::array<double, 4>> waves;
  for (int k = 0; k < 12; ++k)
    waves.push_back({5e-6 * rng.Uniform(0.5, 1), 2 * kPi * static_cast<double>(1 + rng.Below(6)) / (kN * kPitch),
                     2 * kPi * static_cast<double>(1 + rng.Below(6)) / (kN * kPitch), rng.Uniform(0, 2 * kPi)});
  const auto f = Make(
      [&](double x, double y) {
        double s = 0;
        for (const auto& w : waves) s += w[0] * std::sin(w[1] * x + w[2] * y + w[3]);
        return s;
      },
      [&](double x, double y) {
        Eigen::Vector2d g(0, 0);
        for (const auto& w : waves) g += w[0] * std::cos(w[1] * x + w[2] * y + w[3]) * Eigen::Vector2d(w[1], w[2]);
        return g;
      });
  const auto L = DomePreset();
  const auto e = Compare(f, PhotometricStereo(Render(f, L, 0.01, 2, 3), L, {.pitch_m = kPitch}));
  std::printf("rough, 3 shadowed lights: mean normal error %.3f deg, height RMS %.2f %%\n", e.mean_angle_deg, 100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, PlateauWithSmoothStepsRecovered) {
  // A raised plateau (steps up and down, 40 µm, edges 4 pixels wide): periodic, integrable.
  const double H = 40e-6, w = 4 * kPitch, a = kN * kPitch * 0.3, b = kN * kPitch * 0.7;
  auto step = [&](double x) { return 0.5 * (std::tanh((x - a) / w) - std::tanh((x - b) / w)); };
  auto dstep = [&](double x) {
    return 0.5 / w * (1 / std::pow(std::cosh((x - a) / w), 2) - 1 / std::pow(std::cosh((x - b) / w), 2));
  };
  const auto f = Make([&](double x, double) { return H * step(x); }, [&](double x, double) { return Eigen::Vector2d(H * dstep(x), 0); });
  const auto L = DomePreset();
  const auto e = Compare(f, PhotometricStereo(Render(f, L, 0.01, 4), L, {.pitch_m = kPitch}));
  std::printf("plateau: mean normal error %.3f deg, height RMS %.2f %%\n", e.mean_angle_deg, 100 * e.height_rms_fraction);
  EXPECT_LT(e.mean_angle_deg, 2.0);
  EXPECT_LT(e.height_rms_fraction, 0.05);
}

TEST(Photometric, PoissonIntegrationHandlesANonPeriodicTilt) {
  // A tilted plane plus a bump: not periodic, so Frankot-Chellappa's wrap-around distorts it
  // while the Neumann Poisson solve does not.
  const double s = 0.05, A = 10e-6, l = kN * kPitch / 2;
  const auto f = Make([&](double x, double y) { return s * x + A * std::sin(2 * kPi * y / l); },
                      [&](double, double y) { return Eigen::Vector2d(s, A * 2 * kPi / l * std::cos(2 * kPi * y / l)); });
  const auto L = DomePreset();
  const auto imgs = Render(f, L, 0.01, 9);
  const auto poisson = Compare(f, PhotometricStereo(imgs, L, {.pitch_m = kPitch, .integration = Integration::kPoisson}));
  const auto fc = Compare(f, PhotometricStereo(imgs, L, {.pitch_m = kPitch}));
  std::printf("tilt: Poisson height RMS %.2f %%, Frankot-Chellappa %.2f %%\n", 100 * poisson.height_rms_fraction,
              100 * fc.height_rms_fraction);
  EXPECT_LT(poisson.height_rms_fraction, 0.05);
  EXPECT_GT(fc.height_rms_fraction, poisson.height_rms_fraction);
}

TEST(Photometric, SphereNormalsAreExact) {
  // A spherical cap: the classic case with known normals (height not periodic: normals only).
  const double R = kN * kPitch * 0.6, c = kN * kPitch / 2;
  const auto f = Make([&](double x, double y) { return std::sqrt(std::max(R * R - (x - c) * (x - c) - (y - c) * (y - c), 0.0)); },
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
      worst = std::max(worst, std::acos(std::clamp(static_cast<double>(f.n[k].dot(r.normals[k])), -1.0, 1.0)) * 180 / kPi);
    }
  EXPECT_LT(worst, 0.5);
}

TEST(Photometric, CommandLineFromPngsToABuiltModel) {
  test::TempDir dir;
  const double A = 20e-6, l = kN * kPitch / 4;
  const auto f = Make([&](double x, double) { return A * std::sin(2 * kPi * x / l); },
                      [&](double x, double) { return Eigen::Vector2d(A * 2 * kPi / l * std::cos(2 * kPi * x / l), 0); });
  const auto L = DomePreset();
  const auto imgs = Render(f, L, 0.0, 7);
  std::filesystem::create_directory(dir.File("img"));
  for (std::size_t j = 0; j < L.size(); ++j) {
    cv::Mat m(kN, kN, CV_16U);
    for (int i = 0; i < kN * kN; ++i) m.at<std::uint16_t>(i / kN, i % kN) = static_cast<std::uint16_t>(65535 * imgs.images[j][static_cast<std::size_t>(i)]);
    ASSERT_TRUE(cv::imwrite(dir.File("img/" + L[j].file), m));
  }
  std::string out;
  ASSERT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " + dir.File("img") +
                                 " --lights dome --pitch-m 2e-5 -o " + dir.File("h.f32") + " --csv " + dir.File("h.csv") +
                                 " --normals " + dir.File("n.png"), &out), 0) << out;
  EXPECT_TRUE(std::filesystem::exists(dir.File("n.png")));
  test::WriteFile(dir.File("contact.toml"), "[contact]\ntexture_K = 900.0\n\n[friction]\nkappa_N_per_m = 2000.0\nmu_k = 0.3\n");
  test::WriteFile(dir.File("bank.toml"), "[vibration]\nsample_rate_hz = 2000.0\n[[vibration.cells]]\nspeed_mps = 0.08\n"
                                         "force_N = 1.0\nar = [0.5]\nvariance = 1.0\n");
  ASSERT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model build --name Sine --height " + dir.File("h.f32.toml") +
                                 " --contact " + dir.File("contact.toml") + " --vibration " + dir.File("bank.toml") + " -o " +
                                 dir.File("model.toml"), &out), 0) << out;
  const auto m = renderer::LoadMaterial(dir.File("model.toml"));
  EXPECT_EQ(m.geometry->width(), kN);
  EXPECT_NEAR(m.geometry->max_m() - m.geometry->min_m(), 2 * A, 0.05 * 2 * A);  // 16-bit images, no noise
  EXPECT_DOUBLE_EQ(m.friction.mu_k, 0.3);
  // A missing image is named.
  std::filesystem::remove(dir.File("img/light_07.png"));
  EXPECT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " + dir.File("img") +
                                 " --lights dome --pitch-m 2e-5 -o " + dir.File("h2.f32"), &out), 2);
  EXPECT_NE(out.find("light_07.png"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::modeling
