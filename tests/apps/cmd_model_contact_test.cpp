// hapticlab model fit-contact through the command line (apps/hapticlab/cmd_model_contact.cpp):
// on a short simulated measurement of the baseline truth (modeling/workbench_sim.hpp, the
// truth's defaults), the estimates and their intervals, and the written material: what
// the renderer loads is what was reported. ContactCli: on a free-hand measurement
// (tests/modeling/contact_freehand.hpp), `model fit-contact` agrees with `hapticlab fit` and
// `model build` keeps every effect. (Coverage over seeds: ContactFreeHand in
// tests/modeling/contact_test.cpp.)

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "../modeling/contact_freehand.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/modeling/workbench_io.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"
#include "simulate_measurement.hpp"

namespace hapticlab::cmd_model_contact_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(ModelContactCli, FitContactRecoversTheTruthAndTheRendererLoadsWhatWasReported) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv"), model = dir.File("c.toml");
  std::string out;
  ASSERT_EQ(test::SimulateMeasurement("--duration 10 --seed 3", meas, &out), 0) << out;
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
}  // namespace hapticlab::cmd_model_contact_test

namespace hapticlab::modeling::cmd_model_contact_test {
namespace {

// Both commands on one free-hand file, and `model build` keeping every effect.

nlohmann::json RunJson(const std::string& cmd) {
  std::string out;
  EXPECT_EQ(test::RunCommand(cmd, &out), 0) << cmd << "\n" << out;
  return nlohmann::json::parse(out);
}

TEST(ContactCli, FitContactAndWorkbenchFitAgreeAndBuildKeepsEveryEffect) {
  test::TempDir dir;
  const Truth t;
  WriteMeasurementCsv(dir.File("m.csv"), FreeHand(t, 31, 40, 0.008, true));
  const std::string cli = HL_CLI_PATH;
  const auto c = RunJson(cli + " model fit-contact --json --measurement " + dir.File("m.csv") +
                         " -o " + dir.File("c.toml"));
  const auto w = RunJson(cli + " fit --json --quiet --measurement " + dir.File("m.csv") + " -o " +
                         dir.File("w.toml"));
  EXPECT_TRUE(c["usable"].get<bool>());
  EXPECT_TRUE(w["usable"].get<bool>());
  EXPECT_EQ(c["fit"]["friction"]["termination"], "converged");
  // Both commands identify the same model: within 2 % of each other.
  const std::pair<double, double> pairs[] = {
      {c["dahl"]["mu_k"].get<double>(), w["params"]["coulomb"]["mu_k"].get<double>()},
      {c["dahl"]["kappa"].get<double>(), w["params"]["dahl"]["kappa"].get<double>()},
      {c["dahl"]["mu_b"].get<double>(), w["params"]["viscous"]["mu_b"].get<double>()},
      {c["hunt_crossley"]["K1mm_N"].get<double>(), w["params"]["core"]["K1mm_N"].get<double>()},
      {c["hunt_crossley"]["n"].get<double>(), w["params"]["hc-exponent"]["n"].get<double>()},
      {c["hunt_crossley"]["B1mm"].get<double>(), w["params"]["hc-damping"]["B1mm"].get<double>()}};
  for (const auto& [a, b] : pairs) EXPECT_NEAR(a, b, 0.02 * std::abs(b)) << a << " vs " << b;
  EXPECT_NEAR(c["dahl"]["mu_k"].get<double>(), t.mu_k, 0.1 * t.mu_k);

  // model build: a height map, the contact fit and a bank; nothing fitted is lost.
  std::vector<float> h(16 * 16, 0.0f);
  for (int k = 0; k < 256; ++k) h[static_cast<std::size_t>(k)] = 1e-5f * static_cast<float>(k % 16);
  {
    std::ofstream f(dir.File("h.f32"), std::ios::binary);
    f.write(reinterpret_cast<const char*>(h.data()),
            static_cast<std::streamsize>(h.size() * sizeof(float)));
  }
  test::WriteFile(
      dir.File("h.f32.toml"),
      "[geometry]\nkind = \"file\"\nfile = \"h.f32\"\nwidth = 16\nheight = 16\npitch_m = 1e-4\n");
  test::WriteFile(
      dir.File("bank.toml"),
      "[vibration]\nsample_rate_hz = 2000.0\nspeeds_mps = [0.05, 0.1]\nforces_N = [0.5, 1.5]\n"
      "[[vibration.cells]]\nspeed_mps = 0.05\nforce_N = 0.5\nar = [0.5, -0.2]\nvariance = 1.0\n"
      "[[vibration.cells]]\nspeed_mps = 0.05\nforce_N = 1.5\nar = [0.4, -0.2]\nvariance = 2.0\n"
      "[[vibration.cells]]\nspeed_mps = 0.1\nforce_N = 0.5\nar = [0.3, -0.1]\nvariance = 3.0\n"
      "[[vibration.cells]]\nspeed_mps = 0.1\nforce_N = 1.5\nar = [0.2, -0.1]\nvariance = 4.0\n");
  std::string out;
  ASSERT_EQ(
      test::RunCommand(cli + " model build --name Built --height " + dir.File("h.f32.toml") +
                           " --contact " + dir.File("c.toml") + " --vibration " +
                           dir.File("bank.toml") + " --cutoff-hz 90 -o " + dir.File("built.toml"),
                       &out),
      0)
      << out;
  const auto built = renderer::LoadMaterial(dir.File("built.toml"));
  const auto part = renderer::LoadMaterial(dir.File("c.toml"));
  for (const char* e : {"coulomb", "viscous", "dahl", "hc-damping", "hc-exponent",
                        "vibration-speed", "vibration-force"})
    EXPECT_NE(std::find(built.effects.begin(), built.effects.end(), e), built.effects.end()) << e;
  // Every parameter exactly as fitted (the file carries 17 significant digits).
  EXPECT_DOUBLE_EQ(built.contact.texture.K, c["hunt_crossley"]["K"].get<double>());
  EXPECT_DOUBLE_EQ(built.contact.texture.B, c["hunt_crossley"]["B"].get<double>());
  EXPECT_DOUBLE_EQ(built.contact.texture.n, c["hunt_crossley"]["n"].get<double>());
  EXPECT_DOUBLE_EQ(built.friction.kappa_N_per_m, c["dahl"]["kappa"].get<double>());
  EXPECT_DOUBLE_EQ(built.friction.mu_k, c["dahl"]["mu_k"].get<double>());
  EXPECT_DOUBLE_EQ(built.friction.mu_b_Ns_per_m, c["dahl"]["mu_b"].get<double>());
  EXPECT_EQ(built.contact.layer_thickness_m, part.contact.layer_thickness_m);
  EXPECT_EQ(built.vibration.cells.size(), 4u);
  EXPECT_DOUBLE_EQ(built.vibration.cells[3].variance, 4.0);
  EXPECT_EQ(built.geometry->width(), 16);
  EXPECT_DOUBLE_EQ(built.hybrid_cutoff_hz, 90);
  // The workbench replays the built model with its fitted exponent, not n = 1.
  const auto wm = wb::LoadModel(dir.File("built.toml"));
  EXPECT_TRUE(wm.Has("hc-exponent"));
  EXPECT_NEAR(wm.At(wb::key::kN), c["hunt_crossley"]["n"].get<double>(), 1e-12);
  EXPECT_NEAR(wm.At(wb::key::kK1mm_N), c["hunt_crossley"]["K1mm_N"].get<double>(),
              1e-9 * c["hunt_crossley"]["K1mm_N"].get<double>());
  EXPECT_NEAR(wm.At(wb::key::kB1mm_Ns_per_m), c["hunt_crossley"]["B1mm"].get<double>(),
              1e-9 * c["hunt_crossley"]["B1mm"].get<double>());
}

}  // namespace
}  // namespace hapticlab::modeling::cmd_model_contact_test
