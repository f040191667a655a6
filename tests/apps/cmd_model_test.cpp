// hapticlab model: energy, render, check and import-penn through the command line.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "../renderer/penn_xml.hpp"
#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"
#include "sine_model.hpp"

namespace hapticlab::cmd_model_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

constexpr const char* kModel = test::kSineModelToml;

TEST(ModelCli, EnergyOfNormMatchesEquation52WithinOnePercent) {
  std::string out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " model energy --algorithm norm --sine 1e-4,1e-3 --json", &out), 0)
      << out;
  const auto j = nlohmann::json::parse(out);
  const double e = j["energy_J"], c = j["closed_form_J"];
  EXPECT_GT(c, 0);
  EXPECT_NEAR(e, c, 0.01 * c);
}

TEST(ModelCli, CheckReportsBadModelsWithFileLineAndKey) {
  test::TempDir dir;
  test::WriteFile(dir.File("ok.toml"), kModel);
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " model check " + dir.File("ok.toml"), &out), 0) << out;
  std::string bad = kModel;
  bad.replace(bad.find("mu_k = 0.3"), 10, "mu_k = -1.0");
  test::WriteFile(dir.File("bad.toml"), bad);
  EXPECT_EQ(test::RunCommand(Cli() + " model check " + dir.File("bad.toml"), &out), 2);
  EXPECT_NE(out.find("bad.toml"), std::string::npos) << out;
  EXPECT_NE(out.find("friction.mu_k"), std::string::npos) << out;
}

TEST(ModelCli, RenderWritesOneRowPerTrajectorySample) {
  test::TempDir dir;
  test::WriteFile(dir.File("m.toml"), kModel);
  std::string traj = "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m\n";
  for (int k = 0; k < 500; ++k)
    traj += std::to_string(k * 1e-3) + "," + std::to_string(0.05 * k * 1e-3) + ",0,3e-4\n";
  test::WriteFile(dir.File("t.csv"), traj);
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model render --model " + dir.File("m.toml") +
                                 " --trajectory " + dir.File("t.csv") + " --out " +
                                 dir.File("r.csv") + " --vibration-out " + dir.File("v.csv"),
                             &out),
            0)
      << out;
  const auto r = ReadCsv(dir.File("r.csv"));
  ASSERT_EQ(r.rows.size(), 500u);
  // Under the layer top: pushed up with about K d (d = 0.5 mm - 0.3 mm + h), never faulted.
  const double fz = r.Number(250, r.Require("fz_N"));
  EXPECT_NEAR(fz, 900 * (2e-4 + 1e-5), 900 * 1.1e-5);
  EXPECT_EQ(r.Number(250, r.Require("fault")), 0);
  const auto v = ReadCsv(dir.File("v.csv"));
  EXPECT_GT(v.rows.size(), 4900u);
  // A missing column is a usage error naming the file.
  test::WriteFile(dir.File("bad.csv"), "# hapticlab-measurement v1\nt_s,x_m\n0,0\n");
  EXPECT_EQ(
      test::RunCommand(Cli() + " model render --model " + dir.File("m.toml") + " --trajectory " +
                           dir.File("bad.csv") + " --out " + dir.File("r2.csv"),
                       &out),
      2);
  EXPECT_NE(out.find("bad.csv"), std::string::npos) << out;
}

TEST(ModelCli, ImportPennWritesALoadableModel) {
  test::TempDir dir;
  // A minimal single-model set in the toolkit's schema (generated here, not the toolkit's).
  test::WriteFile(dir.File("Models_X.xml"), R"(<?xml version="1.0"?>
<modelSet texture="1"><material>X</material><SampleRate>10000</SampleRate><mu>0.3</mu>
<numMod>1</numMod><speedList type="array"><value>100.0</value></speedList>
<forceList type="array"><value>1.0</value></forceList><numARCoeff>2</numARCoeff>
<model><modNum>1</modNum><ARcoeff><value>1.0</value><value>-0.5</value><value>0.3</value></ARcoeff>
<ARlsf><value>1.0</value><value>2.0</value></ARlsf><var>0.01</var>
<speedMod>100.0</speedMod><forceMod>1.0</forceMod></model></modelSet>
)");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model import-penn --xml " + dir.File("Models_X.xml") +
                                 " -o " + dir.File("x.toml"),
                             &out),
            0)
      << out;
  ASSERT_EQ(test::RunCommand(Cli() + " model check --json " + dir.File("x.toml"), &out), 0) << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["vibration"]["cells"], 1);
  EXPECT_DOUBLE_EQ(j["friction"]["mu_k"].get<double>(), 0.3);
}

// A generated set (tests/renderer/penn_xml.hpp) through import-penn and render: the
// imported model keeps the toolkit's range, plays down to 0.05 mm/s with no hybrid split,
// and render drives it with the trajectory's force.
TEST(ModelCli, ImportPennThenRenderWithTheTrajectorysForce) {
  test::TempDir dir;
  const auto spec = test::MakePennSet(false);
  test::WriteFile(dir.File("Models_G.xml"), test::PennXml(spec));
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model import-penn --xml " + dir.File("Models_G.xml") +
                                 " -o " + dir.File("g.toml"),
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("range 250 mm/s x 2.5 N"), std::string::npos) << out;
  const std::string toml = test::ReadFile(dir.File("g.toml"));
  for (const char* line : {"cutoff_hz = 0\n", "max_speed_mps = 0.25\n", "max_force_N = 2.5\n",
                           "min_speed_mps = 5.0000000000000002e-05\n"})
    EXPECT_NE(toml.find(line), std::string::npos) << line << " in\n" << toml;
  // 3 s at 140 mm/s pressing 1.5 N, the tool 1 mm above the flat geometry: only the
  // trajectory's force says it touches.
  std::string traj =
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n";
  for (int k = 0; k <= 3000; ++k)
    traj += fmt::format("{:.6f},{:.9f},0,0.001,0.14,0,0,0,0,1.5\n", k * 1e-3, 0.14 * k * 1e-3);
  test::WriteFile(dir.File("t.csv"), traj);
  auto vibration_rms = [&](const std::string& extra) {
    EXPECT_EQ(
        test::RunCommand(Cli() + " model render --model " + dir.File("g.toml") + " --trajectory " +
                             dir.File("t.csv") + " --out " + dir.File("r.csv") +
                             " --vibration-out " + dir.File("v.csv") + extra,
                         &out),
        0)
        << out;
    const auto v = ReadCsv(dir.File("v.csv"));
    double s = 0;
    int n = 0;
    for (std::size_t i = 2000; i < v.rows.size(); ++i, ++n)
      s += std::pow(v.Number(i, v.Require("acc_mps2")), 2);
    return std::sqrt(s / std::max(1, n));
  };
  const double expected = std::sqrt(test::PennExpected(spec, 140, 1.5).Power());
  EXPECT_NEAR(vibration_rms("") / expected, 1.0, 0.1);
  EXPECT_EQ(vibration_rms(" --force-source model"), 0.0);  // the rendered force: not in contact
  // Asking for the trajectory's force on a trajectory without one is a usage error.
  test::WriteFile(dir.File("k.csv"),
                  "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m\n0,0,0,0\n0.001,0.0001,0,0\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model render --model " + dir.File("g.toml") +
                                 " --trajectory " + dir.File("k.csv") + " --out " +
                                 dir.File("r.csv") + " --force-source trajectory",
                             &out),
            2);
  EXPECT_NE(out.find("fz_N"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_model_test
