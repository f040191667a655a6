// Photometric stereo on images rendered here from known height fields under the dome.

#include "hapticlab/modeling/photometric.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"
#include "photometric_scenes.hpp"

namespace hapticlab::modeling {
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

TEST(Photometric, CommandLineFromPngsToABuiltModel) {
  test::TempDir dir;
  const double A = 20e-6, l = kN * kPitch / 4;
  const auto f = Make([&](double x, double) { return A * std::sin(2 * kPi * x / l); },
                      [&](double x, double) {
                        return Eigen::Vector2d(A * 2 * kPi / l * std::cos(2 * kPi * x / l), 0);
                      });
  const auto L = DomePreset();
  const auto imgs = Render(f, L, 0.0, 7);
  std::filesystem::create_directory(dir.File("img"));
  for (std::size_t j = 0; j < L.size(); ++j) {
    cv::Mat m(kN, kN, CV_16U);
    for (int i = 0; i < kN * kN; ++i)
      m.at<std::uint16_t>(i / kN, i % kN) =
          static_cast<std::uint16_t>(65535 * imgs.images[j][static_cast<std::size_t>(i)]);
    ASSERT_TRUE(cv::imwrite(dir.File("img/" + L[j].file), m));
  }
  std::string out;
  ASSERT_EQ(
      test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " + dir.File("img") +
                           " --lights dome --pitch-m 2e-5 -o " + dir.File("h.f32") + " --csv " +
                           dir.File("h.csv") + " --normals " + dir.File("n.png"),
                       &out),
      0)
      << out;
  EXPECT_TRUE(std::filesystem::exists(dir.File("n.png")));
  test::WriteFile(
      dir.File("contact.toml"),
      "[contact]\ntexture_K = 900.0\n\n[friction]\nkappa_N_per_m = 2000.0\nmu_k = 0.3\n");
  test::WriteFile(dir.File("bank.toml"),
                  "[vibration]\nsample_rate_hz = 2000.0\n[[vibration.cells]]\nspeed_mps = 0.08\n"
                  "force_N = 1.0\nar = [0.5]\nvariance = 1.0\n");
  ASSERT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model build --name Sine --height " +
                                 dir.File("h.f32.toml") + " --contact " + dir.File("contact.toml") +
                                 " --vibration " + dir.File("bank.toml") + " -o " +
                                 dir.File("model.toml"),
                             &out),
            0)
      << out;
  const auto m = renderer::LoadMaterial(dir.File("model.toml"));
  EXPECT_EQ(m.geometry->width(), kN);
  EXPECT_NEAR(m.geometry->max_m() - m.geometry->min_m(), 2 * A,
              0.05 * 2 * A);  // 16-bit images, no noise
  EXPECT_DOUBLE_EQ(m.friction.mu_k, 0.3);
  // A missing image is named.
  std::filesystem::remove(dir.File("img/light_07.png"));
  EXPECT_EQ(
      test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " + dir.File("img") +
                           " --lights dome --pitch-m 2e-5 -o " + dir.File("h2.f32"),
                       &out),
      2);
  EXPECT_NE(out.find("light_07.png"), std::string::npos) << out;
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

std::string LightsError(const std::string& path) {
  try {
    LoadLights(path);
  } catch (const InputError& e) {
    const auto& d = e.diagnostics().at(0);
    return fmt::format("{}|{}", d.line, d.field);
  }
  return "no error";
}

TEST(Photometric, LightsFilesInTheCommonLayouts) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"csv_header.csv", "file,lx,ly,lz\na.png,0,0,1\nb.png,1,0,1\nc.png,0,1,1\n"},
      {"count_spaces.txt", "3\na.png 0 0 1\nb.png   1 0 1\n\n# comment\nc.png\t0 1 1\r\n"},
      {"angles.txt", "file elevation_deg azimuth_deg\na.png 90 0\nb.png 45 0\nc.png, 45, 90\n"},
      {"csv_plain.csv", "a.png,0,0,2\nb.png,2,0,2\nc.png,0,3,3"},
  };
  for (const auto& [name, text] : files) {
    test::WriteFile(dir.File(name), text);
    const auto L = LoadLights(dir.File(name));
    ASSERT_EQ(L.size(), 3u) << name;
    EXPECT_EQ(L[2].file, "c.png") << name;
    EXPECT_LT((L[0].direction - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12) << name;
    EXPECT_LT((L[1].direction - Eigen::Vector3d(1, 0, 1).normalized()).norm(), 1e-12) << name;
    EXPECT_LT((L[2].direction - Eigen::Vector3d(0, 1, 1).normalized()).norm(), 1e-12) << name;
  }
  EXPECT_EQ(LoadLights(dir.File("count_spaces.txt"))[2].line, 6);
  // DiLiGenT's layout: directions only, names from a list; y up.
  test::WriteFile(dir.File("light_directions.txt"), "0 0 1\n1 0 1\n0 -1 1\n");
  test::WriteFile(dir.File("filenames.txt"), "001.png\n002.png\n003.png\n");
  auto L = LoadLights(dir.File("light_directions.txt"), /*y_up=*/true);
  EXPECT_TRUE(L[0].file.empty());
  ApplyImageList(dir.File("filenames.txt"), L);
  EXPECT_EQ(L[1].file, "002.png");
  EXPECT_LT((L[2].direction - Eigen::Vector3d(0, 1, 1).normalized()).norm(), 1e-12);
  test::WriteFile(dir.File("short_list.txt"), "001.png\n002.png\n");
  EXPECT_THROW(ApplyImageList(dir.File("short_list.txt"), L), InputError);
  // Errors name the right line and field, with or without a count line or header.
  test::WriteFile(dir.File("e1.txt"), "3\na.png 0 0 1\nb.png 1 x 1\nc.png 0 1 1\n");
  EXPECT_EQ(LightsError(dir.File("e1.txt")), "3|ly");
  test::WriteFile(dir.File("e2.csv"), "a.png,0,0,1\nb.png,0,0,-1\nc.png,0,1,1\n");
  EXPECT_EQ(LightsError(dir.File("e2.csv")), "2|lz");
  test::WriteFile(dir.File("e3.txt"), "4\na.png 0 0 1\nb.png 1 0 1\nc.png 0 1 1\n");
  EXPECT_EQ(LightsError(dir.File("e3.txt")), "1|");
  test::WriteFile(dir.File("e4.txt"),
                  "# rig B\nfile,lx,ly,lz\na.png,0,0,1\nb.png,1,0,1\nc.png,0,1\n");
  EXPECT_EQ(LightsError(dir.File("e4.txt")), "5|");
  test::WriteFile(dir.File("e5.txt"), "file,x,y,z\na.png,0,0,1\n");
  EXPECT_EQ(LightsError(dir.File("e5.txt")), "1|file");
  test::WriteFile(dir.File("e6.txt"), "a.png 40 0\nb.png -5 90\nc.png 40 180\n");
  EXPECT_EQ(LightsError(dir.File("e6.txt")), "2|elevation_deg");
}

// TGA bytes (the Truevision layout) for a w x h image given top row first.
std::vector<unsigned char> Tga(int type, int bpp, bool top_left, int w, int h,
                               const std::vector<unsigned char>& data) {
  std::vector<unsigned char> f(18, 0);
  f[2] = static_cast<unsigned char>(type);
  f[12] = static_cast<unsigned char>(w);
  f[14] = static_cast<unsigned char>(h);
  f[16] = static_cast<unsigned char>(bpp);
  f[17] = static_cast<unsigned char>((top_left ? 0x20 : 0) | (bpp == 32 ? 8 : 0));
  for (const unsigned char c : data) f.push_back(c);
  return f;
}

void WriteBytes(const std::string& path, const std::vector<unsigned char>& b) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(b.data(), 1, b.size(), f);
  std::fclose(f);
}

TEST(Photometric, TgaImagesReadLikeThePngsOfTheSamePixels) {
  test::TempDir dir;
  const int w = 5, h = 4;
  // Grey, uncompressed, bottom-left origin (rows stored bottom first).
  cv::Mat grey(h, w, CV_8U);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      grey.at<unsigned char>(i, j) = static_cast<unsigned char>(40 * i + 7 * j + 3);
  std::vector<unsigned char> g;
  for (int i = h - 1; i >= 0; --i)
    for (int j = 0; j < w; ++j) g.push_back(grey.at<unsigned char>(i, j));
  WriteBytes(dir.File("g.tga"), Tga(3, 8, false, w, h, g));
  ASSERT_TRUE(cv::imwrite(dir.File("g.png"), grey));
  // Colour, RLE, top-left origin: row 0 one run of 5 equal pixels, then raw packets.
  cv::Mat colour(h, w, CV_8UC3);
  std::vector<unsigned char> rle = {0x84, 10, 200, 90};
  for (int j = 0; j < w; ++j) colour.at<cv::Vec3b>(0, j) = cv::Vec3b(10, 200, 90);
  for (int i = 1; i < h; ++i) {
    rle.push_back(static_cast<unsigned char>(w - 1));
    for (int j = 0; j < w; ++j) {
      const cv::Vec3b px(static_cast<unsigned char>(30 * j), static_cast<unsigned char>(60 * i),
                         static_cast<unsigned char>(5 * i * j));
      colour.at<cv::Vec3b>(i, j) = px;
      rle.insert(rle.end(), {px[0], px[1], px[2]});
    }
  }
  WriteBytes(dir.File("c.tga"), Tga(10, 24, true, w, h, rle));
  ASSERT_TRUE(cv::imwrite(dir.File("c.png"), colour));
  for (const std::string base : {"g", "c"}) {
    int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
    const auto a = ReadGreyImage(dir.File(base + ".tga"), &w1, &h1),
               b = ReadGreyImage(dir.File(base + ".png"), &w2, &h2);
    ASSERT_EQ(w1, w);
    ASSERT_EQ(h1, h);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k], b[k]) << base << " pixel " << k;
  }
  // A truncated file is an input error naming it.
  auto bytes = Tga(3, 8, false, w, h, g);
  bytes.resize(bytes.size() - 3);
  WriteBytes(dir.File("t.tga"), bytes);
  int ww = 0, hh = 0;
  EXPECT_THROW(ReadGreyImage(dir.File("t.tga"), &ww, &hh), InputError);
}

TEST(Photometric, CommandLineDiLiGenTLayoutMaskFrameAndFloatOutputs) {
  // The layout of DiLiGenT-style data: 001.png ..., light_directions.txt (y up, directions
  // only), filenames.txt, mask.png.
  test::TempDir dir;
  const auto s = MakeSphere(64, 28, 0.9);
  const auto L = TwelveLights();
  const auto img = RenderSphere(s, L, 0.6, 40.0, 21);
  std::string dirs, names;
  for (std::size_t j = 0; j < L.size(); ++j) {
    const std::string name = fmt::format("{:03d}.png", j + 1);
    cv::Mat m(s.n, s.n, CV_16U);
    for (int i = 0; i < s.n * s.n; ++i)
      m.at<std::uint16_t>(i / s.n, i % s.n) = static_cast<std::uint16_t>(
          std::lround(65535 * img.images[j][static_cast<std::size_t>(i)]));
    ASSERT_TRUE(cv::imwrite(dir.File(name), m));
    dirs += fmt::format("{:.9f} {:.9f} {:.9f}\n", L[j].direction.x(), -L[j].direction.y(),
                        L[j].direction.z());
    names += name + "\n";
  }
  test::WriteFile(dir.File("light_directions.txt"), dirs);
  test::WriteFile(dir.File("filenames.txt"), names);
  cv::Mat mask(s.n, s.n, CV_8UC3, cv::Scalar::all(0));
  for (int i = 0; i < s.n * s.n; ++i)
    if (s.mask[static_cast<std::size_t>(i)])
      mask.at<cv::Vec3b>(i / s.n, i % s.n) = cv::Vec3b(0, 0, 255);  // red: colour masks count
  ASSERT_TRUE(cv::imwrite(dir.File("mask.png"), mask));
  const std::string base = std::string(HL_CLI_PATH) + " model photometric --images " + dir.path() +
                           " --lights " + dir.File("light_directions.txt") + " --image-list " +
                           dir.File("filenames.txt") + " --mask " + dir.File("mask.png") +
                           " --pitch-m 2e-5 -o " + dir.File("h.f32");
  std::string out;
  ASSERT_EQ(test::RunCommand(base + " --lights-y-up --normals " + dir.File("n.tiff") +
                                 " --albedo " + dir.File("a.tiff"),
                             &out),
            0)
      << out;
  EXPECT_EQ(out.find("warning"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(base + " --lights-y-up --normals " + dir.File("n.png") + " --albedo " +
                                 dir.File("a.png"),
                             &out),
            0)
      << out;
  const cv::Mat nf = cv::imread(dir.File("n.tiff"), cv::IMREAD_UNCHANGED),
                n8 = cv::imread(dir.File("n.png"), cv::IMREAD_UNCHANGED),
                af = cv::imread(dir.File("a.tiff"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(nf.type(), CV_32FC3);
  ASSERT_EQ(n8.type(), CV_8UC3);
  ASSERT_EQ(af.type(), CV_32FC1);
  std::vector<double> err;
  double bias = 0, off_by_more = 0, cnt = 0;
  for (int i = 0; i < s.n; ++i)
    for (int j = 0; j < s.n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i * s.n + j);
      const auto v = nf.at<cv::Vec3f>(i, j);  // B, G, R = z, y, x; y up in this run
      if (!s.mask[k]) {
        EXPECT_EQ(v, cv::Vec3f(0, 0, 0));
        EXPECT_EQ(af.at<float>(i, j), 0.f);
        continue;
      }
      const Eigen::Vector3f truth_y_up(s.normals[k].x(), -s.normals[k].y(), s.normals[k].z());
      err.push_back(AngleDeg(truth_y_up, Eigen::Vector3f(v[2], v[1], v[0])));
      const auto p = n8.at<cv::Vec3b>(i, j);
      for (int c = 0; c < 3; ++c) {
        const double exact = 127.5 * (static_cast<double>(v[c]) + 1);
        bias += p[c] - exact;
        off_by_more += std::abs(p[c] - exact) > 0.5 + 1e-4 ? 1 : 0;
        cnt += 1;
      }
    }
  std::nth_element(err.begin(), err.begin() + static_cast<std::ptrdiff_t>(err.size() / 2),
                   err.end());
  std::printf("CLI, DiLiGenT layout with highlights: median normal error %.3f deg\n",
              err[err.size() / 2]);
  EXPECT_LT(err[err.size() / 2], 1.0);
  EXPECT_EQ(off_by_more, 0);              // every 8-bit value is the float rounded ...
  EXPECT_LT(std::abs(bias / cnt), 0.05);  // ... so no half-step bias (truncation gives -0.5)
  // Without --lights-y-up the same run warns about the mirrored frame.
  ASSERT_EQ(test::RunCommand(base, &out), 0) << out;
  EXPECT_NE(out.find("--lights-y-up"), std::string::npos) << out;
  // Bad input: exit 2 naming the file, line and field.
  test::WriteFile(dir.File("bad.txt"),
                  "12\n" + dirs.substr(0, dirs.find('\n')) + "\n0.1 0.2 oops\n");
  EXPECT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " +
                                 dir.path() + " --lights " + dir.File("bad.txt") +
                                 " --pitch-m 2e-5 -o " + dir.File("x.f32"),
                             &out),
            2);
  EXPECT_NE(out.find("bad.txt:3: lz"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(base + " --integration frankot-chellappa", &out), 2);
  EXPECT_NE(out.find("--integration"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(base + " --normals " + dir.File("n.jpg"), &out), 2);
  test::WriteFile(dir.File("no_names.txt"), dirs);
  EXPECT_EQ(test::RunCommand(std::string(HL_CLI_PATH) + " model photometric --images " +
                                 dir.path() + " --lights " + dir.File("no_names.txt") +
                                 " --pitch-m 2e-5 -o " + dir.File("x.f32"),
                             &out),
            2);
  EXPECT_NE(out.find("--image-list"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::modeling
