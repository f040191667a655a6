// hapticlab model photometric through the command line (apps/hapticlab/cmd_model_photometric.cpp):
// a tilted plane photographed under eight lights (16-bit binary PGM files written here byte by
// byte, a lights file 'file lx ly lz') comes back as a plane of that slope in every output; the
// option checks name the option. (The solver on rough, shadowed and masked surfaces, the dome
// preset and DiLiGenT layouts: tests/modeling/photometric_test.cpp.)

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
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
}  // namespace hapticlab
