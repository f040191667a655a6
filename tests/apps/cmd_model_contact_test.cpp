// hapticlab model fit-contact through the command line (apps/hapticlab/cmd_model_contact.cpp):
// on a short simulated measurement of the baseline truth (modeling/workbench_sim.hpp
// TruthParams defaults), the estimates and their intervals, and the written material: what
// the renderer loads is what was reported. (Agreement with `hapticlab fit` and `model build`:
// ContactCli in tests/modeling/contact_test.cpp; coverage over seeds: ContactFreeHand there.)

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(ModelContactCli, FitContactRecoversTheTruthAndTheRendererLoadsWhatWasReported) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv"), model = dir.File("c.toml");
  std::string out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " measurement simulate --duration 10 --seed 3 -o " + meas + " > /dev/null", &out),
      0)
      << out;
  ASSERT_EQ(test::RunCommand(
                Cli() + " model fit-contact --json --measurement " + meas + " -o " + model, &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_TRUE(j["usable"].get<bool>());
  EXPECT_GT(j["samples"]["pokes"].get<int>(), 100);
  EXPECT_GT(j["samples"]["strokes"].get<int>(), 1000);
  const std::map<std::string, double> truth = {{"K1mm_N", 1.5}, {"n", 1.3},    {"B1mm", 20},
                                               {"kappa", 3000}, {"mu_k", 0.3}, {"mu_b", 0.5}};
  for (const auto& [k, v] : truth) {
    const auto& e = j["uncertainty"][k];
    const double value = e["value"];
    EXPECT_NEAR(value / v, 1.0, 0.05) << k;
    EXPECT_LT(e["lo95"].get<double>(), value) << k;
    EXPECT_GT(e["hi95"].get<double>(), value) << k;
    EXPECT_GT(e["sd"].get<double>(), 0) << k;
  }
  EXPECT_DOUBLE_EQ(j["dahl"]["mu_k"].get<double>(),
                   j["uncertainty"]["mu_k"]["value"].get<double>());
  // The material written: `model check` reads back the reported K, B, n, kappa, mu_k, mu_b.
  ASSERT_EQ(test::RunCommand(Cli() + " model check --json " + model, &out), 0) << out;
  const auto m = nlohmann::json::parse(out.substr(out.find('{')));
  EXPECT_NEAR(m["texture"]["K"].get<double>() / j["hunt_crossley"]["K"].get<double>(), 1, 1e-12);
  EXPECT_NEAR(m["texture"]["B"].get<double>() / j["hunt_crossley"]["B"].get<double>(), 1, 1e-12);
  EXPECT_NEAR(m["texture"]["n"].get<double>(), j["hunt_crossley"]["n"].get<double>(), 1e-12);
  EXPECT_NEAR(m["friction"]["kappa_N_per_m"].get<double>(), j["dahl"]["kappa"].get<double>(), 1e-9);
  EXPECT_NEAR(m["friction"]["mu_k"].get<double>(), j["dahl"]["mu_k"].get<double>(), 1e-12);
  EXPECT_NEAR(m["friction"]["mu_b_Ns_per_m"].get<double>(), j["dahl"]["mu_b"].get<double>(), 1e-12);
  EXPECT_EQ(m["effects"],
            nlohmann::json::array({"coulomb", "viscous", "dahl", "hc-damping", "hc-exponent"}));
}

TEST(ModelContactCli, BadMeasurementsAreNamedWithFileLineAndColumn) {
  test::TempDir dir;
  std::string out;
  test::WriteFile(dir.File("nofz.csv"),
                  "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N\n"
                  "0,0,0,0,0,0,0,0,0\n0.001,0,0,0,0,0,0,0,0\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-contact --measurement " + dir.File("nofz.csv") +
                                 " -o " + dir.File("c.toml"),
                             &out),
            2);
  EXPECT_NE(out.find("nofz.csv"), std::string::npos) << out;
  EXPECT_NE(out.find("fz_N"), std::string::npos) << out;
  test::WriteFile(
      dir.File("bad.csv"),
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n"
      "0,0,0,-0.001,0.01,0,0,-0.3,0,1\n0.001,x,0,-0.001,0.01,0,0,-0.3,0,1\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-contact --measurement " + dir.File("bad.csv") +
                                 " -o " + dir.File("c.toml"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("bad.csv") + ":4: x_m"), std::string::npos) << out;
  // A --pokes file that does not exist is named too.
  test::WriteFile(
      dir.File("good.csv"),
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n"
      "0,0,0,-0.001,0.01,0,0,-0.3,0,1\n0.001,0.00001,0,-0.001,0.01,0,0,-0.3,0,1\n");
  EXPECT_EQ(test::RunCommand(Cli() + " model fit-contact --measurement " + dir.File("good.csv") +
                                 " --pokes " + dir.File("none.csv") + " -o " + dir.File("c.toml"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("none.csv")), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("c.toml")));
}

}  // namespace
}  // namespace hapticlab
