// hapticlab model fit-vibration / fit-neural / cv-vibration / cutoff through the command line
// (apps/hapticlab/cmd_model_vibration.cpp).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_model_vibration_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// A 3 x 3 grid of recordings of a known resonant process (short, for the command line).
void WriteGrid(const std::string& dir) {
  int k = 0;
  for (double v : {0.04, 0.08, 0.12})
    for (double f : {0.54, 1.18, 1.91}) {
      std::string s = "# hapticlab-measurement v1\n# speed_mps: " + std::to_string(v) +
                      "\n# force_N: " + std::to_string(f) + "\nt_s,x_m,y_m,z_m,acc_mps2\n";
      double a1 = 0, a2 = 0;
      std::uint64_t state = 12345 + static_cast<std::uint64_t>(k);
      for (int i = 0; i < 6000; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        const double e = static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5;
        const double a = 1.6 * a1 - 0.9 * a2 + (0.5 + v) * e;
        a2 = a1;
        a1 = a;
        s += std::to_string(i / 2000.0) + ",0,0,0," + std::to_string(a) + "\n";
      }
      test::WriteFile(dir + "/r" + std::to_string(k++) + ".csv", s);
    }
}

// model cutoff reads the whole recording (before issue #33, silently its first 20 000
// samples), or the first --max-seconds.
TEST(ModelCli, CutoffTestsTheWholeRecordingOrTheWindowAsked) {
  test::TempDir dir;
  std::string s =
      "# hapticlab-measurement v1\n# speed_mps: 0.08\n# force_N: 1.2\n"
      "t_s,x_m,y_m,z_m,acc_mps2\n";
  double a1 = 0, a2 = 0;
  std::uint64_t state = 99;
  for (int i = 0; i < 30000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double e = static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5;
    const double a = 1.6 * a1 - 0.9 * a2 + e;
    a2 = a1;
    a1 = a;
    s += std::to_string(i / 2000.0) + ",0,0,0," + std::to_string(a) + "\n";
  }
  test::WriteFile(dir.File("long.csv"), s);
  std::string out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " model cutoff --json --recording " + dir.File("long.csv"), &out), 0)
      << out;
  auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["samples"], 30000);
  EXPECT_NEAR(j["seconds"].get<double>(), 15.0, 1e-6);
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " model cutoff --json --max-seconds 2 --recording " + dir.File("long.csv"), &out),
      0)
      << out;
  j = nlohmann::json::parse(out);
  EXPECT_EQ(j["samples"], 4000);
}

TEST(ModelCli, FitVibrationCrossValidateAndCutoff) {
  test::TempDir dir;
  std::filesystem::create_directory(dir.File("rec"));
  WriteGrid(dir.File("rec"));
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model fit-vibration --recordings " + dir.File("rec") +
                                 " -o " + dir.File("bank.toml") + " --order 4",
                             &out),
            0)
      << out;
  // The bank plugs into a material model through [vibration] file = ...
  test::WriteFile(dir.File("m.toml"),
                  "name = \"x\"\n[contact]\ntexture_K = 100.0\n[friction]\nkappa_N_per_m = 100.0\n"
                  "mu_k = 0.2\n[vibration]\nfile = \"bank.toml\"\n");
  ASSERT_EQ(test::RunCommand(Cli() + " model check --json " + dir.File("m.toml"), &out), 0) << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["vibration"]["cells"], 9);
  EXPECT_EQ(j["vibration"]["order"], 4);
  ASSERT_EQ(test::RunCommand(Cli() + " model cv-vibration --recordings " + dir.File("rec") +
                                 " --order 4 --json --plots " + dir.File("plots"),
                             &out),
            0)
      << out;
  EXPECT_TRUE(std::filesystem::exists(dir.File("plots/spectrum_v80_f118.png")));
  EXPECT_GT(std::filesystem::file_size(dir.File("plots/spectrum_v80_f118.svg")), 1000u);
  const auto cv = nlohmann::json::parse(out);
  EXPECT_EQ(cv["conditions"].size(), 9u);
  for (const char* k : {"speed_mps", "force_N", "split", "es"})
    EXPECT_TRUE(cv["conditions"][0].contains(k)) << k;
  EXPECT_TRUE(cv.contains("mean_es_train"));
  ASSERT_EQ(test::RunCommand(
                Cli() + " model cutoff --recording " + dir.File("rec/r0.csv") + " --json", &out),
            0)
      << out;
  EXPECT_EQ(nlohmann::json::parse(out)["cutoff_hz"],
            50.0);  // already stationary at the first cut-off
  // Issue #33: it says so, with the statistic, and the test ran on the whole recording.
  EXPECT_TRUE(nlohmann::json::parse(out)["stationary_at_every_cutoff"].get<bool>()) << out;
  EXPECT_EQ(nlohmann::json::parse(out)["samples"], 6000) << out;
  ASSERT_EQ(test::RunCommand(Cli() + " model cutoff --recording " + dir.File("rec/r0.csv"), &out),
            0)
      << out;
  EXPECT_NE(out.find("stationary at every tested cut-off: already at the lowest, 50.0 Hz (ADF -"),
            std::string::npos)
      << out;
  // The AR order cap is an option, and an order at the cap is reported as such.
  ASSERT_EQ(test::RunCommand(Cli() + " model fit-vibration --recordings " + dir.File("rec") +
                                 " -o " + dir.File("bank1.toml") + " --max-order 1",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("order 1 (the --max-order cap: the aic may prefer more)"), std::string::npos)
      << out;
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-vibration --recordings " + dir.File("rec") +
                                 " -o " + dir.File("bank0.toml") + " --max-order 0",
                             &out),
            2)
      << out;
  // A folder without recordings is bad input.
  std::filesystem::create_directory(dir.File("empty"));
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-vibration --recordings " + dir.File("empty") +
                                 " -o " + dir.File("b.toml"),
                             &out),
            2);
}

TEST(ModelCli, FitNeuralAndCrossValidateEveryModelKind) {
  test::TempDir dir;
  std::filesystem::create_directory(dir.File("rec"));
  WriteGrid(dir.File("rec"));
  std::string out;
  for (const char* topo : {"unified", "decomposed"}) {
    const auto file = dir.File(std::string("n_") + topo + ".toml");
    ASSERT_EQ(test::RunCommand(Cli() + " model fit-neural --recordings " + dir.File("rec") +
                                   " --topology " + topo + " --epochs 2 -o " + file,
                               &out),
              0)
        << out;
    EXPECT_NE(out.find("networks trained"), std::string::npos) << "progress: " << out;
    test::WriteFile(
        dir.File("m.toml"),
        "name = \"x\"\n[contact]\ntexture_K = 100.0\n[friction]\nkappa_N_per_m = 100.0\n"
        "mu_k = 0.2\n[neural]\nfile = \"" +
            std::string("n_") + topo + ".toml\"\n");
    EXPECT_EQ(test::RunCommand(Cli() + " model check " + dir.File("m.toml"), &out), 0) << out;
  }
  // One E_s table for the three kinds (Fig. 3.7): same conditions, same keys.
  for (const char* kind : {"lpc", "neural-unified", "neural-decomposed"}) {
    ASSERT_EQ(test::RunCommand(
                  Cli() + " model cv-vibration --recordings " + dir.File("rec") + " --model-kind " +
                      kind + " --epochs 2 --train-speeds 0.04,0.12 --train-forces 0.54,1.91 --json",
                  &out),
              0)
        << out;
    const auto j = nlohmann::json::parse(out.substr(out.find('{')));
    EXPECT_EQ(j["model_kind"], kind);
    EXPECT_EQ(j["conditions"].size(), 9u);
    EXPECT_TRUE(j["mean_es_test"].get<double>() > 0);
  }
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " model cv-vibration --recordings " + dir.File("rec") + " --model-kind nn", &out),
      2);
  // A grid with a hole cannot train Γ_D.
  std::filesystem::remove(dir.File("rec/r4.csv"));
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-neural --recordings " + dir.File("rec") +
                                 " --epochs 1 -o " + dir.File("x.toml"),
                             &out),
            2);
  EXPECT_NE(out.find("full speed x force grid"), std::string::npos) << out;
}

// The grid's process is a known AR(2), a_k = 1.6 a_{k-1} - 0.9 a_{k-2} + e_k with e_k uniform
// of SD (0.5 + v) / sqrt(12): the bank's order-2 cells recover its coefficients, and their
// innovation variances grow with speed like (0.5 + v)^2 (the bank file read line by line here).
TEST(ModelCli, FitVibrationRecoversTheRecordedArProcess) {
  test::TempDir dir;
  std::filesystem::create_directory(dir.File("rec"));
  WriteGrid(dir.File("rec"));
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " model fit-vibration --recordings " + dir.File("rec") +
                                 " -o " + dir.File("bank.toml") + " --order 2 --band-low 0",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("9 recordings -> 9 cells (grid), order 2 at 2000 Hz"), std::string::npos)
      << out;
  std::istringstream in(test::ReadFile(dir.File("bank.toml")));
  std::string line;
  std::vector<double> speed, variance;
  int cells = 0;
  while (std::getline(in, line)) {
    double a = 0, b = 0;
    if (line.rfind("speed_mps = ", 0) == 0) speed.push_back(std::stod(line.substr(12)));
    if (line.rfind("variance = ", 0) == 0) variance.push_back(std::stod(line.substr(11)));
    if (std::sscanf(line.c_str(), "ar = [%lf, %lf]", &a, &b) == 2) {
      ++cells;
      EXPECT_NEAR(a, 1.6, 0.03) << line;
      EXPECT_NEAR(b, -0.9, 0.03) << line;
    }
  }
  ASSERT_EQ(cells, 9);
  ASSERT_EQ(speed.size(), 9u);
  ASSERT_EQ(variance.size(), 9u);
  for (std::size_t k = 0; k < 9; ++k) {
    const double e = (0.5 + speed[k]) * (0.5 + speed[k]) / 12;
    EXPECT_NEAR(variance[k] / e, 1.0, 0.12) << "cell " << k;
    // Relative to the slowest cell of the same force (the grid is written speed-major).
    if (k >= 3) {
      EXPECT_NEAR(variance[k] / variance[k % 3],
                  std::pow((0.5 + speed[k]) / (0.5 + speed[k % 3]), 2), 0.05)
          << "cell " << k;
    }
  }
}

TEST(ModelCli, VibrationOptionsAreCheckedAndNamed) {
  test::TempDir dir;
  std::filesystem::create_directory(dir.File("rec"));
  WriteGrid(dir.File("rec"));
  const std::string rec = " --recordings " + dir.File("rec");
  std::string out;
  for (const char* order : {"0", "65", "two"}) {
    EXPECT_EQ(test::RunCommand(Cli() + " model fit-vibration" + rec + " -o " + dir.File("b.toml") +
                                   " --order " + order,
                               &out),
              2)
        << order;
    EXPECT_NE(out.find("<command line>: --order: expected"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("b.toml")));
  EXPECT_EQ(test::RunCommand(Cli() + " model cv-vibration" + rec + " --train-speeds 0.04,x", &out),
            2);
  EXPECT_NE(out.find("--train-speeds: expected comma-separated numbers, got '0.04,x'"),
            std::string::npos)
      << out;
  // A recording without acc_mps2: the file is named.
  test::WriteFile(dir.File("noacc.csv"), "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m\n0,0,0,0\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model cutoff --recording " + dir.File("noacc.csv"), &out),
            2);
  EXPECT_NE(out.find("noacc.csv: acc_mps2: column is missing"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_model_vibration_test
