// hapticlab fit through the command line (apps/hapticlab/cmd_workbench_fit.cpp): on a short
// simulated measurement of the baseline truth (modeling/workbench_sim.hpp; the defaults of
// TruthParams and the effects' TruthSpecs: K1mm 1.5 N, n 1.3, B1mm 20 N s/m, mu_k 0.3,
// kappa 3000 N/m, mu_b 0.5 N s/m), the estimates, and the written model: its renderer tables
// in SI units from the workbench's parameters (K = K1mm / (1 mm)^n). (fit --add and held-out
// errors: WorkbenchCli.FromRawMeasurementToImprovedModel in cmd_workbench_test.cpp.)

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hapticlab/test/test_util.hpp"
#include "simulate_measurement.hpp"

namespace hapticlab::cmd_workbench_fit_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// "key = number" lines of a TOML file by table ("contact.texture_K",
// "workbench.params.coulomb.mu_k").
std::map<std::string, double> Numbers(const std::string& text) {
  std::map<std::string, double> out;
  std::istringstream in(text);
  std::string line, table;
  while (std::getline(in, line)) {
    if (line.rfind("[", 0) == 0) {
      table = line.substr(1, line.find(']') - 1);
      continue;
    }
    const auto eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    try {
      const double v = std::stod(line.substr(eq + 3));
      out[table + "." + line.substr(0, eq)] = v;
    } catch (const std::exception&) {
    }
  }
  return out;
}

TEST(WorkbenchFitCli, RecoversTheTruthAndWritesTheRendererTablesFromTheParameters) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv"), model = dir.File("f.toml");
  std::string out;
  ASSERT_EQ(test::SimulateMeasurement("--duration 10 --seed 3", meas, &out), 0) << out;
  // --quiet: stdout only (the JSON); nothing on stderr.
  ASSERT_EQ(test::RunCommand("{ " + Cli() + " fit --json --quiet --measurement " + meas + " -o " +
                                 model + " 2> " + dir.File("err.txt") + "; }",
                             &out),
            0)
      << out;
  EXPECT_EQ(test::ReadFile(dir.File("err.txt")), "");
  const auto j = nlohmann::json::parse(out);
  EXPECT_TRUE(j["usable"].get<bool>());
  EXPECT_EQ(j["before"], j["after"]) << "no --model and no --add: one fit, reported once";
  const std::map<std::string, std::map<std::string, double>> truth = {
      {"core", {{"K1mm_N", 1.5}}},  {"hc-exponent", {{"n", 1.3}}}, {"hc-damping", {{"B1mm", 20}}},
      {"coulomb", {{"mu_k", 0.3}}}, {"dahl", {{"kappa", 3000}}},   {"viscous", {{"mu_b", 0.5}}}};
  for (const auto& [effect, ps] : truth)
    for (const auto& [name, value] : ps) {
      const double v = j["params"][effect][name];
      EXPECT_NEAR(v / value, 1.0, 0.05) << effect << "." << name << " = " << v;
    }
  // The file: [workbench.params.*] hold the reported parameters, and the renderer's tables
  // follow from them in SI units.
  const auto f = Numbers(test::ReadFile(model));
  for (const auto& [effect, ps] : j["params"].items())
    for (const auto& [name, v] : ps.items())
      EXPECT_DOUBLE_EQ(f.at("workbench.params." + effect + "." + name), v.get<double>())
          << effect << "." << name;
  const double n = j["params"]["hc-exponent"]["n"];
  const double mm_n = std::pow(1e-3, n);
  EXPECT_DOUBLE_EQ(f.at("contact.texture_n"), n);
  EXPECT_NEAR(f.at("contact.texture_K") * mm_n / j["params"]["core"]["K1mm_N"].get<double>(), 1,
              1e-12);
  EXPECT_NEAR(f.at("contact.texture_B") * mm_n / j["params"]["hc-damping"]["B1mm"].get<double>(), 1,
              1e-12);
  EXPECT_DOUBLE_EQ(f.at("friction.mu_k"), j["params"]["coulomb"]["mu_k"].get<double>());
  EXPECT_DOUBLE_EQ(f.at("friction.kappa_N_per_m"), j["params"]["dahl"]["kappa"].get<double>());
  EXPECT_DOUBLE_EQ(f.at("friction.mu_b_Ns_per_m"), j["params"]["viscous"]["mu_b"].get<double>());
  // The renderer loads what was written.
  EXPECT_EQ(test::RunCommand(Cli() + " model check " + model, &out), 0) << out;
}

// Issue #33's hidden-effect case: strokes whose low-speed friction falls with speed (a
// Stribeck law, dmu_s 0.25 over v_s 4 mm/s, and no viscous friction in the truth). The
// baseline's viscous term would fit a negative mu_b; it stops at its bound 0, and the
// bootstrap's bias correction once pushed it to -0.000123, so `fit` wrote a model it then
// refused to read (exit 2) and `diagnose` could not run. Now: exit 0, mu_b at its bound with an
// interval from it, a model that loads, and `diagnose` ranks stribeck first.
TEST(WorkbenchFitCli, StribeckStrokesFitWithMuBAtItsBoundAndDiagnoseRanksStribeckFirst) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv"), model = dir.File("f.toml");
  std::string out;
  ASSERT_EQ(test::SimulateMeasurement("--duration 60 --seed 5 --effects coulomb dahl stribeck "
                                      "hc-damping hc-exponent vibration-speed vibration-force",
                                      meas, &out),
            0)
      << out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " fit --json --quiet --measurement " + meas + " -o " + model, &out),
      0)
      << out;
  const auto j = nlohmann::json::parse(out);
  const auto& mu_b = j["estimates"]["viscous"]["mu_b"];
  EXPECT_EQ(mu_b["value"].get<double>(), 0.0) << mu_b.dump();
  EXPECT_EQ(mu_b["lo95"].get<double>(), 0.0) << "the interval runs from the bound";
  EXPECT_GE(mu_b["hi95"].get<double>(), 0.0);
  EXPECT_EQ(j["params"]["viscous"]["mu_b"].get<double>(), 0.0);
  for (const auto& p : j["friction_bootstrap"]["params"]) {
    EXPECT_GE(p["corrected"].get<double>(), 0.0) << p.dump();  // every friction parameter >= 0
    if (p["name"] == "mu_b" && p["fit"].get<double>() - p["bias"].get<double>() < 0) {
      EXPECT_TRUE(p["at_bound"].get<bool>()) << p.dump();
    }
  }
  EXPECT_EQ(test::RunCommand(Cli() + " model check " + model, &out), 0) << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " diagnose --json --quiet --model " + model + " --measurement " + meas, &out),
      0)
      << out;
  const auto dx = nlohmann::json::parse(out);
  ASSERT_FALSE(dx["candidates"].empty());
  EXPECT_EQ(dx["candidates"][0]["effect"], "stribeck") << dx["candidates"].dump(1);
}

TEST(WorkbenchFitCli, BadInputNamesTheFileOrTheOptionBeforeAnyWork) {
  test::TempDir dir;
  std::string out;
  // An unknown effect is refused before the (missing) measurement is even opened.
  EXPECT_EQ(test::RunCommand(Cli() + " fit --measurement " + dir.File("none.csv") +
                                 " --add frictionless -o " + dir.File("o.toml"),
                             &out),
            2);
  EXPECT_NE(out.find("<command line>: --add: unknown effect 'frictionless'"), std::string::npos)
      << out;
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " fit --measurement " + dir.File("none.csv") + " -o " + dir.File("o.toml"), &out),
      2);
  EXPECT_NE(out.find(dir.File("none.csv")), std::string::npos) << out;
  test::WriteFile(dir.File("bad.toml"), "name = \"x\"\n[friction]\nmu_k = \"high\"\n");
  EXPECT_EQ(test::RunCommand(Cli() + " fit --measurement " + dir.File("none.csv") + " --model " +
                                 dir.File("bad.toml") + " -o " + dir.File("o.toml"),
                             &out),
            2);
  EXPECT_NE(out.find("bad.toml:3: friction.mu_k: expected a number"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("o.toml")));
}

}  // namespace
}  // namespace hapticlab::cmd_workbench_fit_test
