// hapticlab compare through the command line (apps/hapticlab/cmd_workbench_compare.cpp): a
// short simulated measurement of the baseline truth compared with the truth's own force model
// (written here from the simulator's documented defaults, modeling/workbench_sim.hpp) and with
// the same model with mu_k 0.06 too high. (Plots, --before and the text report's order:
// WorkbenchCli.FromRawMeasurementToImprovedModel in cmd_workbench_test.cpp.)

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "hapticlab/test/test_util.hpp"
#include "simulate_measurement.hpp"

namespace hapticlab::cmd_workbench_compare_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// The truth's force effects as a renderer material: K = K1mm / (1 mm)^n, B = B1mm / (1 mm)^n.
std::string TruthModel(double mu_k) {
  const double mm_n = std::pow(1e-3, 1.3);
  return "name = \"truth\"\neffects = [\"coulomb\", \"viscous\", \"dahl\", \"hc-damping\", "
         "\"hc-exponent\"]\n[contact]\ntexture_K = " +
         std::to_string(1.5 / mm_n) + "\ntexture_B = " + std::to_string(20 / mm_n) +
         "\ntexture_n = 1.3\nlayer_thickness_m = 0.005\n[friction]\nkappa_N_per_m = 3000.0\n"
         "mu_k = " +
         std::to_string(mu_k) + "\nmu_b_Ns_per_m = 0.5\n";
}

TEST(WorkbenchCompareCli, AWrongFrictionCoefficientShowsAsAConstantFrictionRatioResidual) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv");
  std::string out;
  ASSERT_EQ(test::SimulateMeasurement("--duration 10 --seed 3", meas, &out), 0) << out;
  test::WriteFile(dir.File("truth.toml"), TruthModel(0.3));
  test::WriteFile(dir.File("wrong.toml"), TruthModel(0.36));
  auto compare = [&](const std::string& model) {
    EXPECT_EQ(
        test::RunCommand(
            Cli() + " compare --json --model " + dir.File(model) + " --measurement " + meas, &out),
        0)
        << out;
    return nlohmann::json::parse(out);
  };
  const auto t = compare("truth.toml"), w = compare("wrong.toml");
  // Residual = measured - model: the friction ratio is 0.06 below the wrong model's wherever it
  // slides, at every load, speed and time; the truth leaves none. (Bins of 100 samples or more;
  // Dahl's pre-sliding transients pull the mean a little towards zero.)
  for (const char* dim : {"load", "speed", "time"}) {
    int bins = 0;
    for (const auto& [cmp, lo, hi] :
         {std::tuple(&t, -0.005, 0.005), std::tuple(&w, -0.066, -0.050)})
      for (const auto& row : (*cmp)["breakdown"][dim]["friction_ratio"])
        if (row["n"].get<int>() >= 100) {
          EXPECT_GE(row["mean"].get<double>(), lo) << dim << " " << row.dump();
          EXPECT_LE(row["mean"].get<double>(), hi) << dim << " " << row.dump();
          ++bins;
        }
    EXPECT_GE(bins, 4) << dim;
  }
  // Only friction changed: the normal-force channel is the same, the friction channel worse,
  // and the largest systematic residual of the wrong model is a friction one.
  EXPECT_DOUBLE_EQ(w["channels"]["normal_force"].get<double>(),
                   t["channels"]["normal_force"].get<double>());
  EXPECT_GT(w["channels"]["friction"].get<double>(), 4 * t["channels"]["friction"].get<double>());
  EXPECT_GT(w["error"].get<double>(), t["error"].get<double>());
  ASSERT_FALSE(w["summary"]["largest"].empty());
  EXPECT_EQ(w["summary"]["largest"][0]["quantity"].get<std::string>().rfind("friction", 0), 0u)
      << w["summary"]["largest"][0];
  // Every dimension bins the same normal-force samples.
  int n_regime = 0;
  for (const auto& row : t["breakdown"]["regime"]["normal_force_N"])
    n_regime += row["n"].get<int>();
  EXPECT_GT(n_regime, 1000);
  for (const auto& [dim, qs] : t["breakdown"].items()) {
    if (!qs.contains("normal_force_N")) continue;
    int n = 0;
    for (const auto& row : qs["normal_force_N"]) n += row["n"].get<int>();
    EXPECT_EQ(n, n_regime) << dim;
  }
}

TEST(WorkbenchCompareCli, AMissingModelOrMeasurementIsNamed) {
  test::TempDir dir;
  test::WriteFile(dir.File("truth.toml"), TruthModel(0.3));
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " compare --model " + dir.File("none.toml") +
                                 " --measurement " + dir.File("m.csv"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("none.toml") + ": cannot open"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " compare --model " + dir.File("truth.toml") +
                                 " --measurement " + dir.File("m.csv"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("m.csv")), std::string::npos) << out;
}

// Issue #33: a model whose vibration is a renderer AR bank (the dissertation's own LPC model,
// from `model fit-vibration`) is scored by compare beside the force channels, with E_s by speed
// and force; the same bank with 100 times the amplitude (far above the simulated measurement's
// level) scores worse in every condition. The workbench's own band model is scored as before.
TEST(WorkbenchCompareCli, AnArBanksVibrationIsScoredBySpeedAndForce) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv");
  std::string out;
  ASSERT_EQ(test::SimulateMeasurement("--duration 5 --seed 3", meas, &out), 0) << out;
  // 2 x 2 AR(1) banks, written by hand in the renderer's format, at two levels.
  for (const char* variance : {"1.0", "10000.0"}) {
    std::string bank =
        "[vibration]\nsample_rate_hz = 2000.0\nmin_speed_mps = 0.01\nspeeds_mps = [0.04, 0.12]\n"
        "forces_N = [0.5, 1.5]\n";
    for (const char* v : {"0.04", "0.12"})
      for (const char* f : {"0.5", "1.5"})
        bank += std::string("[[vibration.cells]]\nspeed_mps = ") + v + "\nforce_N = " + f +
                "\nar = [0.5]\nvariance = " + variance + "\n";
    test::WriteFile(dir.File(std::string("bank") + variance + ".toml"), bank);
    test::WriteFile(dir.File(std::string("ar") + variance + ".toml"),
                    "name = \"x\"\n[contact]\ntexture_K = 1000.0\n[friction]\nkappa_N_per_m = "
                    "3000.0\nmu_k = 0.3\n[vibration]\nfile = \"bank" +
                        std::string(variance) + ".toml\"\n");
  }
  std::map<std::string, nlohmann::json> by;
  for (const char* variance : {"1.0", "10000.0"}) {
    const std::string model = dir.File(std::string("ar") + variance + ".toml");
    ASSERT_EQ(test::RunCommand(
                  Cli() + " compare --json --model " + model + " --measurement " + meas, &out),
              0)
        << out;
    auto j = nlohmann::json::parse(out);
    EXPECT_TRUE(j["channels"].contains("vibration")) << out;
    EXPECT_NE(j["vibration_model"].get<std::string>().find("an AR bank (4 cells, order 1"),
              std::string::npos)
        << out;
    ASSERT_FALSE(j["vibration_by_condition"].empty()) << out;
    by[variance] = j;
  }
  EXPECT_GT(by["10000.0"]["channels"]["vibration"].get<double>(),
            by["1.0"]["channels"]["vibration"].get<double>());
  const auto& loud = by["10000.0"]["vibration_by_condition"];
  const auto& quiet = by["1.0"]["vibration_by_condition"];
  ASSERT_EQ(loud.size(), quiet.size());
  for (std::size_t k = 0; k < loud.size(); ++k) {
    EXPECT_EQ(loud[k]["condition"], quiet[k]["condition"]);
    EXPECT_GT(loud[k]["es"].get<double>(), quiet[k]["es"].get<double>()) << loud[k]["condition"];
  }
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " compare --model " + dir.File("ar1.0.toml") + " --measurement " + meas, &out),
      0)
      << out;
  EXPECT_NE(out.find("vibration E_s by speed and force:"), std::string::npos) << out;
  EXPECT_EQ(out.find("not scored"), std::string::npos) << out;
  // The workbench's fitted model has the band model: scored, nothing refused.
  ASSERT_EQ(test::RunCommand(Cli() + " fit --quiet --measurement " + meas + " -o " +
                                 dir.File("f.toml") + " > /dev/null",
                             &out),
            0)
      << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " compare --json --model " + dir.File("f.toml") + " --measurement " + meas, &out),
      0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_TRUE(j["channels"].contains("vibration")) << out;
  EXPECT_EQ(j["vibration_model"], "");
}

}  // namespace
}  // namespace hapticlab::cmd_workbench_compare_test
