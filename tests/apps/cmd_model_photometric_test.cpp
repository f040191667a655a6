// hapticlab model photometric through the command line (apps/hapticlab/cmd_model_photometric.cpp):
// a tilted plane photographed under eight lights (16-bit binary PGM files written here byte by
// byte, a lights file 'file lx ly lz') comes back as a plane of that slope in every output; the
// option checks name the option. Scenes of tests/modeling/photometric_scenes.hpp written as
// image files: a sinusoid under the dome preset through to a built model, and a sphere in
// DiLiGenT's layout (mask, y-up lights, float outputs). (The solver itself on rough, shadowed
// and masked surfaces: tests/modeling/photometric_test.cpp.)

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../modeling/photometric_scenes.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_model_photometric_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

constexpr int kW = 24, kH = 16;
constexpr double kSlope = 0.3;     // dz/dx of the plane
constexpr double kPitch_m = 1e-4;  // per pixel

// Lambertian image of the plane z = kSlope x (image frame: x right, y down, z to the camera)
// lit from direction l, as a 16-bit binary PGM (big-endian samples).
void WritePlanePgm(const std::string& path, const double l[3]) {
  const double norm = std::sqrt(kSlope * kSlope + 1);
  const double shade = (-kSlope * l[0] + l[2]) / norm;  // n . l, n = (-kSlope, 0, 1) / norm
  ASSERT_GT(shade, 0.1) << "the test's lights must all light the plane";
  const auto v = static_cast<unsigned>(std::lround(50000 * shade));
  std::ofstream f(path, std::ios::binary);
  f << "P5\n" << kW << " " << kH << "\n65535\n";
  for (int i = 0; i < kW * kH; ++i) {
    f.put(static_cast<char>(v >> 8));
    f.put(static_cast<char>(v & 0xff));
  }
  ASSERT_TRUE(f.good()) << path;
}

// Eight lights at 30 and 50 degrees from the camera axis, four azimuths each.
std::string WriteScene(const test::TempDir& dir) {
  std::filesystem::create_directory(dir.File("img"));
  std::string lights;
  int k = 0;
  for (const double el : {30.0, 50.0})
    for (const double az : {0.0, 90.0, 180.0, 270.0}) {
      const double t = el * std::numbers::pi / 180, p = az * std::numbers::pi / 180;
      const double l[3] = {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
      const std::string name = "l" + std::to_string(k++) + ".pgm";
      WritePlanePgm(dir.File("img/" + name), l);
      lights += name + " " + std::to_string(l[0]) + " " + std::to_string(l[1]) + " " +
                std::to_string(l[2]) + "\n";
    }
  test::WriteFile(dir.File("lights.txt"), lights);
  return " --images " + dir.File("img") + " --lights " + dir.File("lights.txt") + " --pitch-m " +
         std::to_string(kPitch_m);
}

TEST(PhotometricCli, ATiltedPlaneComesBackWithItsSlope) {
  test::TempDir dir;
  const std::string scene = WriteScene(dir);
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model photometric" + scene + " --integration poisson -o " +
                                 dir.File("h.f32") + " --csv " + dir.File("h.csv"),
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("24x16 height map"), std::string::npos) << out;
  // CSV: one image row per line, heights above the lowest point, rising kSlope per metre of x.
  std::istringstream csv(test::ReadFile(dir.File("h.csv")));
  std::string line;
  int rows = 0;
  const double range = kSlope * kPitch_m * (kW - 1);
  while (std::getline(csv, line)) {
    std::vector<double> h;
    std::stringstream cells(line);
    std::string c;
    while (std::getline(cells, c, ',')) h.push_back(std::stod(c));
    ASSERT_EQ(h.size(), static_cast<std::size_t>(kW)) << "row " << rows;
    for (int j = 0; j < kW; ++j)
      EXPECT_NEAR(h[static_cast<std::size_t>(j)], kSlope * kPitch_m * j, 0.01 * range)
          << "row " << rows << " col " << j;
    ++rows;
  }
  EXPECT_EQ(rows, kH);
  // The raw float32 map holds the same heights, row-major, and its [geometry] table says so.
  const auto raw_size = std::filesystem::file_size(dir.File("h.f32"));
  EXPECT_EQ(raw_size, sizeof(float) * kW * kH);
  std::ifstream raw(dir.File("h.f32"), std::ios::binary);
  std::vector<float> f(kW * kH);
  raw.read(reinterpret_cast<char*>(f.data()), static_cast<std::streamsize>(raw_size));
  EXPECT_NEAR(f[kW - 1], range, 0.01 * range);
  EXPECT_NEAR(f[(kH - 1) * kW], 0, 0.01 * range);
  const std::string geom = test::ReadFile(dir.File("h.f32.toml"));
  for (const char* s :
       {"kind = \"file\"", "file = \"h.f32\"", "width = 24", "height = 16", "pitch_m = 0.0001"})
    EXPECT_NE(geom.find(s), std::string::npos) << s << " in\n" << geom;
}

TEST(PhotometricCli, OptionsAndLightsAreCheckedBeforeAnyWork) {
  test::TempDir dir;
  const std::string scene = WriteScene(dir);
  const std::string o = " -o " + dir.File("h.f32");
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " model photometric" + scene + o + " --normals n.jpg", &out),
            2);
  EXPECT_NE(out.find("--normals: n.jpg: .png (8/16-bit) or .tif/.tiff"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " model photometric" + scene + o + " --albedo a.bmp", &out),
            2);
  EXPECT_NE(out.find("--albedo"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " model photometric" + scene + o + " --mask " +
                                 dir.File("img/l0.pgm") + " --integration frankot-chellappa",
                             &out),
            2);
  EXPECT_NE(out.find("--integration: frankot-chellappa integrates the whole image"),
            std::string::npos)
      << out;
  // Directions without image names: the lights file and line of the first one are named.
  test::WriteFile(dir.File("dirs.txt"), "# directions only\n0 0 1\n0.5 0 0.866\n0 0.5 0.866\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model photometric --images " + dir.File("img") +
                                 " --lights " + dir.File("dirs.txt") + " --pitch-m 1e-4" + o,
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("dirs.txt") + ":2: file: no image name for this light"),
            std::string::npos)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("h.f32")));
}

}  // namespace
}  // namespace hapticlab::cmd_model_photometric_test

// The scenes rendered to image files and run through the command line.
namespace hapticlab::modeling::cmd_model_photometric_test {
namespace {

using namespace scenes;  // NOLINT(google-build-using-namespace): the shared test scenes

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
}  // namespace hapticlab::modeling::cmd_model_photometric_test
