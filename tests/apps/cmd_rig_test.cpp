// hapticlab rig show / check / calibrate through the command line (apps/hapticlab/cmd_rig.cpp;
// the --clock real timing check: rig_timing_test.cpp).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_rig_test {
namespace {

std::string RigCli() { return std::string(HL_CLI_PATH); }
std::string Cli() { return HL_CLI_PATH; }

TEST(RigCli, CheckShowAndCalibrate) {
  test::TempDir dir;
  std::string out;
  // The Falcon twin through the engine: JSON with the link's counters; the rest pose is out of
  // contact.
  ASSERT_EQ(
      test::RunCommand(
          RigCli() + " rig check --device falcon-twin --seconds 1 --empty-reads 0.1 --json", &out),
      0)
      << out;
  const auto j = nlohmann::json::parse(out.substr(out.find('{')));
  EXPECT_EQ(j["device"], "falcon-twin");
  EXPECT_EQ(j["ticks"], 1000);
  EXPECT_GT(j["empty_reads"].get<int>(), 50);
  EXPECT_EQ(j["lost"], 0);
  EXPECT_EQ(j["home_in_contact"], false);
  EXPECT_EQ(j["faulted"], false);
  EXPECT_GT(j["contact_ticks"].get<int>(), 500);
  // A rig file whose left sample sits where the grip rests: the check says so (exit 1).
  ASSERT_EQ(test::RunCommand(RigCli() + " rig show --device falcon > /dev/null", &out), 0) << out;
  ASSERT_EQ(test::RunCommand(RigCli() + " rig calibrate " + dir.File("none.toml") +
                                 " --points '-0.01,0,0;0.01,0,0;0,0.01,0'",
                             &out),
            2)
      << out;
  // Calibrate the left sample from four touches on the plane y = 0.01 (above the grip's rest pose).
  test::WriteFile(dir.File("touches.csv"),
                  "x_m,y_m,z_m\n-0.03,0.01,0.10\n0.0,0.01,0.10\n-0.03,0.01,0.14\n0.0,0.01,0.14\n");
  test::WriteFile(
      dir.File("rig.toml"),
      "device = \"falcon\"\n[sample.left]\norigin_m = [-0.025, -0.04, 0.125]\nx_axis = [1, 0, "
      "0]\nz_axis = [0, 1, 0]\n"
      "[sample.right]\norigin_m = [0.025, -0.04, 0.125]\nx_axis = [1, 0, 0]\nz_axis = [0, 1, 0]\n");
  ASSERT_EQ(test::RunCommand(RigCli() + " rig calibrate " + dir.File("rig.toml") +
                                 " --side left --points " + dir.File("touches.csv") + " --out " +
                                 dir.File("new.toml"),
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("residual RMS 0.000 mm"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(RigCli() + " rig show " + dir.File("new.toml") + " --json", &out), 0)
      << out;
  const auto s = nlohmann::json::parse(out.substr(out.find('{')));
  EXPECT_NEAR(s["samples"]["left"]["device"]["origin_m"][1].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(s["samples"]["left"]["device"]["z_axis"][1].get<double>(), 1.0, 1e-9);
  // The left sample now sits where the grip rests: rig check refuses it.
  EXPECT_EQ(test::RunCommand(RigCli() + " rig check --device falcon-twin --seconds 0.1 --rig " +
                                 dir.File("new.toml"),
                             &out),
            1)
      << out;
  EXPECT_NE(out.find("IN CONTACT"), std::string::npos) << out;
  // A malformed touch names the file and line.
  test::WriteFile(dir.File("bad.csv"), "0,0,0\n0.01,0,zero\n");
  EXPECT_EQ(test::RunCommand(RigCli() + " rig calibrate " + dir.File("rig.toml") + " --points " +
                                 dir.File("bad.csv"),
                             &out),
            2);
  EXPECT_NE(out.find("bad.csv:2"), std::string::npos) << out;
}

// Touches on a plane tilted by 30 degrees, in a checker pattern +-0.1 mm off it, with a stylus
// tip offset and a translated device: the least-squares plane is the true one (the pattern is
// symmetric), every residual is 0.1 mm, and the pose is written in both frames.
TEST(RigCli, CalibrateFitsATiltedPlaneThroughTheTipsAndKeepsTheDevicePose) {
  test::TempDir dir;
  const double th = 30 * 3.14159265358979323846 / 180, c = std::cos(th), s = std::sin(th);
  const double n[3] = {0, c, s}, u[3] = {1, 0, 0}, v[3] = {0, -s, c};  // normal, in-plane axes
  const double centre[3] = {0.01, 0.02, 0.12}, tip[3] = {0, 0, -0.003}, d = 1e-4, h = 0.02;
  std::string pts;
  const double corners[4][3] = {{-h, -h, +d}, {+h, -h, -d}, {-h, +h, -d}, {+h, +h, +d}};
  char num[40];
  for (const auto& k : corners) {
    for (int i = 0; i < 3; ++i) {  // the device reports the tip minus the offset
      std::snprintf(num, sizeof num, "%.15g%c",
                    centre[i] + k[0] * u[i] + k[1] * v[i] + k[2] * n[i] - tip[i],
                    i < 2 ? ',' : ';');
      pts += num;
    }
  }
  pts.pop_back();
  test::WriteFile(dir.File("rig.toml"),
                  "device = \"falcon\"\n[device_pose]\norigin_m = [0.1, 0, 0]\nx_axis = [1, 0, 0]\n"
                  "z_axis = [0, 0, 1]\n[stylus]\ntip_offset_m = [0, 0, -0.003]\n"
                  "[sample.left]\norigin_m = [0.075, -0.04, 0.125]\nx_axis = [1, 0, 0]\n"
                  "z_axis = [0, 1, 0]\n[sample.right]\norigin_m = [0.125, -0.04, 0.125]\n"
                  "x_axis = [1, 0, 0]\nz_axis = [0, 1, 0]\n");
  std::string out;
  // No --out: the rig file on stdout, the fit on stderr.
  ASSERT_EQ(test::RunCommand("{ " + Cli() + " rig calibrate " + dir.File("rig.toml") +
                                 " --points '" + pts + "' > " + dir.File("new.toml") + "; }",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("from 4 touches"), std::string::npos) << out;
  EXPECT_NE(out.find("residual RMS 0.100 mm, max 0.100 mm"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(Cli() + " rig show " + dir.File("new.toml") + " --json 2>&1", &out), 0)
      << out;
  const auto j = nlohmann::json::parse(out.substr(out.find('{')));
  const auto& dev = j["samples"]["left"]["device"];
  const auto& world = j["samples"]["left"]["world"];
  const double kDigits = 2e-6;  // the rig file keeps 6 significant digits
  for (int i = 0; i < 3; ++i) {
    // The device frame is the reported point's: the tip at the origin reports origin - tip.
    EXPECT_NEAR(dev["origin_m"][i].get<double>(), centre[i] - tip[i], kDigits) << i;
    EXPECT_NEAR(dev["z_axis"][i].get<double>(), n[i], kDigits) << i;
    EXPECT_NEAR(dev["x_axis"][i].get<double>(), u[i], kDigits) << i;
    EXPECT_NEAR(world["origin_m"][i].get<double>(), centre[i] + (i == 0 ? 0.1 : 0), kDigits) << i;
  }
  // The right sample is untouched.
  EXPECT_NEAR(j["samples"]["right"]["world"]["origin_m"][0].get<double>(), 0.125, 1e-12);
  // --up on the other side flips the normal; x still follows the first two touches.
  ASSERT_EQ(test::RunCommand(Cli() + " rig calibrate " + dir.File("rig.toml") + " --points '" +
                                 pts + "' --up 0,-1,0 --out " + dir.File("down.toml"),
                             &out),
            0)
      << out;
  ASSERT_EQ(test::RunCommand(Cli() + " rig show " + dir.File("down.toml") + " --json", &out), 0);
  const auto k = nlohmann::json::parse(out.substr(out.find('{')))["samples"]["left"]["device"];
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(k["z_axis"][i].get<double>(), -n[i], kDigits) << i;
    EXPECT_NEAR(k["x_axis"][i].get<double>(), u[i], kDigits) << i;
  }
  // Bad input: --up that is not three numbers, two touches only.
  EXPECT_EQ(test::RunCommand(Cli() + " rig calibrate " + dir.File("rig.toml") + " --points '" +
                                 pts + "' --up 0,1",
                             &out),
            2);
  EXPECT_NE(out.find("<command line>: --up: expected x,y,z"), std::string::npos) << out;
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " rig calibrate " + dir.File("rig.toml") + " --points '0,0,0;0.01,0,0'", &out),
      2);
  EXPECT_NE(out.find("points"), std::string::npos) << out;
}

// `rig init` writes a template `rig show` reads back, for every device the rig file supports.
TEST(RigCli, InitWritesATemplateThatShowReads) {
  test::TempDir dir;
  std::string out;
  for (const char* device : {"falcon", "sim", "falcon-twin"}) {
    const std::string file = dir.File(std::string(device) + ".toml");
    ASSERT_EQ(test::RunCommand(RigCli() + " rig init --device " + device + " -o " + file, &out), 0)
        << out;
    EXPECT_EQ(test::ReadFile(file).rfind("# Rig-file template", 0), 0u) << "commented";
    ASSERT_EQ(test::RunCommand(RigCli() + " rig show " + file + " --json", &out), 0) << out;
    const auto j = nlohmann::json::parse(out.substr(out.find('{')));
    EXPECT_EQ(j["device"], device);
  }
  EXPECT_EQ(test::RunCommand(RigCli() + " rig init --device nosuch", &out), 2) << out;
}

// Set a rig up by touching it: a rig file whose left sample is 2 cm off and tilted; the
// simulated hand on the Falcon twin touches four points of the left sample where it truly lies
// (the built-in Falcon rig: origin [-0.025, -0.04, 0.125] m, x along device x, normal along
// device y); `rig touch` records them through the Falcon back-end (encoders, kinematics) and
// `rig calibrate` recovers the true pose.
TEST(RigCli, TouchOnTheFalconTwinRecordsPointsCalibrateTurnsIntoTheTruePose) {
  test::TempDir dir;
  std::string out;
  test::WriteFile(
      dir.File("rig.toml"),
      "device = \"falcon\"\n[sample.left]\norigin_m = [-0.005, -0.03, 0.11]\nx_axis = [1, 0, "
      "0.2]\nz_axis = [0.1, 1, 0]\n"
      "[sample.right]\norigin_m = [0.025, -0.04, 0.125]\nx_axis = [1, 0, 0]\nz_axis = [0, 1, 0]\n");
  // Sample-frame targets: the first two along +x, centred on the sample's origin.
  ASSERT_EQ(
      test::RunCommand(RigCli() + " rig touch --device falcon-twin --rig " + dir.File("rig.toml") +
                           " --script '-0.012,-0.01,0;0.012,-0.01,0;0.012,0.01,0;-0.012,0.01,0'"
                           " -o " +
                           dir.File("touch.csv"),
                       &out),
      0)
      << out;
  EXPECT_NE(out.find("point 4:"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(RigCli() + " rig calibrate " + dir.File("rig.toml") +
                                 " --side left --points " + dir.File("touch.csv") + " --out " +
                                 dir.File("new.toml"),
                             &out),
            0)
      << out;
  ASSERT_EQ(test::RunCommand(RigCli() + " rig show " + dir.File("new.toml") + " --json", &out), 0)
      << out;
  const auto left = nlohmann::json::parse(out.substr(out.find('{')))["samples"]["left"]["device"];
  const double truth_origin[3] = {-0.025, -0.04, 0.125};
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(left["origin_m"][k].get<double>(), truth_origin[k], 0.5e-3) << k;
  auto angle_deg = [](const nlohmann::json& a, double x, double y, double z) {
    const double ax = a[0], ay = a[1], az = a[2];
    const double c = (ax * x + ay * y + az * z) / std::sqrt(ax * ax + ay * ay + az * az);
    return std::acos(std::min(1.0, c)) * 180 / 3.14159265358979;
  };
  EXPECT_LT(angle_deg(left["z_axis"], 0, 1, 0), 1.0) << left.dump();
  EXPECT_LT(angle_deg(left["x_axis"], 1, 0, 0), 1.0) << left.dump();
  // Before calibration the file was off by far more than that (the test could fail).
  ASSERT_EQ(test::RunCommand(RigCli() + " rig show " + dir.File("rig.toml") + " --json", &out), 0);
  const auto before = nlohmann::json::parse(out.substr(out.find('{')))["samples"]["left"]["device"];
  EXPECT_GT(std::abs(before["origin_m"][0].get<double>() - truth_origin[0]), 0.01);
  EXPECT_GT(angle_deg(before["z_axis"], 0, 1, 0), 5.0);
  // Scripted touches drive a simulated hand only.
  EXPECT_EQ(
      test::RunCommand(RigCli() + " rig touch --device falcon --script '0,0,0;1,0,0;0,1,0'", &out),
      2)
      << out;
}

}  // namespace
}  // namespace hapticlab::cmd_rig_test
