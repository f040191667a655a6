// hapticlab measurement / effects through the command line (apps/hapticlab/cmd_workbench.cpp),
// and the workbench's worked example of docs/workbench.md end to end on a short simulated
// measurement: measurement simulate, check, fit, diagnose, fit --add, compare (the commands'
// own tests: cmd_workbench_fit_test.cpp, cmd_workbench_compare_test.cpp,
// cmd_workbench_diagnose_test.cpp).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_workbench_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

nlohmann::json Json(const std::string& cmd) {
  std::string out;
  EXPECT_EQ(test::RunCommand(cmd, &out), 0) << cmd << "\n" << out;
  return nlohmann::json::parse(out);
}

TEST(WorkbenchCli, FromRawMeasurementToImprovedModel) {
  test::TempDir dir;
  const auto meas = dir.File("meas.csv");
  std::string out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " measurement simulate --add load-dependent-friction --duration 60 --seed 3 -o " +
              meas,
          &out),
      0)
      << out;
  const auto check = Json(Cli() + " measurement check --json " + meas);
  EXPECT_NEAR(check["rate_hz"].get<double>(), 2000, 1e-6);
  EXPECT_EQ(check["gaps"], 0);
  EXPECT_TRUE(check["has_acceleration"].get<bool>());

  const auto base = dir.File("base.toml");
  const auto fit = Json(Cli() + " fit --json --quiet --measurement " + meas + " -o " + base);
  EXPECT_TRUE(std::filesystem::exists(base));
  EXPECT_EQ(fit["effects"].size(), 7u);
  // Every solve's summary and every parameter's interval.
  EXPECT_TRUE(fit["usable"].get<bool>());
  ASSERT_EQ(fit["fits"].size(), 3u);
  for (const auto& f : fit["fits"]) {
    EXPECT_EQ(f["termination"], "converged") << f.dump();
    for (const char* k : {"iterations", "final_cost", "at_bounds", "usable"})
      EXPECT_TRUE(f.contains(k)) << k;
  }
  const auto& mu = fit["estimates"]["coulomb"]["mu_k"];
  EXPECT_LT(mu["lo95"].get<double>(), mu["value"].get<double>());
  EXPECT_GT(mu["hi95"].get<double>(), mu["value"].get<double>());
  // Without --add nothing changes: one line for the fit, one held out; progress on stderr
  // unless --quiet.
  ASSERT_EQ(
      test::RunCommand(Cli() + " fit --measurement " + meas + " -o " + dir.File("b2.toml"), &out),
      0)
      << out;
  EXPECT_EQ(out.find("before"), std::string::npos) << out;
  EXPECT_NE(out.find("fitted:"), std::string::npos) << out;
  EXPECT_NE(out.find("fit: fitting on all data"), std::string::npos) << out;
  EXPECT_NE(out.find("friction fit: converged"), std::string::npos) << out;

  const auto dx =
      Json(Cli() + " diagnose --json --quiet --model " + base + " --measurement " + meas);
  ASSERT_FALSE(dx["candidates"].empty());
  const auto& top = dx["candidates"][0];
  EXPECT_EQ(top["effect"], "load-dependent-friction") << dx.dump(2);
  EXPECT_TRUE(top["supported"].get<bool>());
  EXPECT_LT(top["params"]["alpha"].get<double>(), 1.0);  // the truth's friction grows like f_n^0.7
  EXPECT_GT(top["error_reduction"].get<double>(), 0);
  for (std::size_t i = 1; i < dx["candidates"].size(); ++i)
    EXPECT_LE(dx["candidates"][i]["error_reduction"].get<double>(),
              dx["candidates"][i - 1]["error_reduction"].get<double>());
  EXPECT_NEAR(dx["baseline_error"].get<double>(),
              top["error_after"].get<double>() + top["error_reduction"].get<double>(), 1e-12);
  // The unexplained report, keys as documented.
  ASSERT_TRUE(dx.contains("unexplained"));
  ASSERT_FALSE(dx["unexplained"]["channels"].empty());
  for (const auto& c : dx["unexplained"]["channels"])
    for (const char* k : {"channel", "error", "noise_floor", "ratio"})
      EXPECT_TRUE(c.contains(k)) << k;
  ASSERT_FALSE(dx["unexplained"]["axes"].empty());
  const std::set<std::string> axes = {"time",     "speed",  "load", "direction",
                                      "position", "regime", "band"};
  for (const auto& a : dx["unexplained"]["axes"]) {
    for (const char* k : {"axis", "channel", "share", "description"})
      EXPECT_TRUE(a.contains(k)) << k;
    EXPECT_TRUE(axes.count(a["axis"].get<std::string>())) << a.dump();
  }
  EXPECT_FALSE(dx["unexplained"]["flagged"].get<bool>()) << "an effect is supported";

  const auto better = dir.File("better.toml");
  const auto fit2 = Json(Cli() + " fit --json --quiet --measurement " + meas + " --model " + base +
                         " --add load-dependent-friction -o " + better);
  EXPECT_LT(fit2["held_out"]["after"]["channels"]["friction"].get<double>(),
            0.5 * fit2["held_out"]["before"]["channels"]["friction"].get<double>());

  const auto plots = dir.File("plots");
  const auto cmp = Json(Cli() + " compare --json --model " + better + " --measurement " + meas +
                        " --plots " + plots + " --before " + base);
  EXPECT_GT(cmp["error"].get<double>(), 0);
  EXPECT_FALSE(cmp["summary"]["axes"].empty());
  EXPECT_FALSE(cmp["summary"]["largest"].empty());
  // The text report opens with the summary, the bin-by-bin detail after it.
  ASSERT_EQ(test::RunCommand(Cli() + " compare --model " + base + " --measurement " + meas, &out),
            0)
      << out;
  const auto where = out.find("where the residual lives"), detail = out.find("detail:");
  ASSERT_NE(where, std::string::npos) << out;
  ASSERT_NE(detail, std::string::npos) << out;
  EXPECT_LT(where, detail);
  EXPECT_LT(out.find("largest systematic residuals"), detail);
  for (const char* dim : {"regime", "speed", "load", "direction", "position", "time", "band"})
    EXPECT_TRUE(cmp["breakdown"].contains(dim)) << dim;
  EXPECT_TRUE(std::filesystem::exists(plots + "/residual_load_friction_ratio.png"));
  EXPECT_TRUE(std::filesystem::exists(plots + "/trace_friction.svg"));
  // The renderer plays the fitted model.
  EXPECT_EQ(test::RunCommand(Cli() + " model check " + better, &out), 0) << out;
}

TEST(WorkbenchCli, BadInputIsReportedWithFileLineAndColumn) {
  test::TempDir dir;
  const auto meas = dir.File("m.csv");
  test::WriteFile(meas,
                  "# hapticlab-measurement v1\n# material: "
                  "x\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n"
                  "0,0,0,-0.001,0.01,0,0,-0.3,0,1\n0.001,0.00001,0,-0.001,0.01,0,0,-0.3,zero,1\n");
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " measurement check " + meas, &out), 2);
  EXPECT_NE(out.find("m.csv:5"), std::string::npos) << out;
  EXPECT_NE(out.find("fy_N"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " fit --measurement " + meas + " --add no-such-effect -o " +
                                 dir.File("o.toml"),
                             &out),
            2);
  EXPECT_EQ(test::RunCommand(
                Cli() + " measurement simulate --add no-such-effect -o " + dir.File("s.csv"), &out),
            2);
  EXPECT_NE(out.find("stribeck"), std::string::npos) << "lists the catalogue: " << out;
  EXPECT_EQ(test::RunCommand(Cli() + " effects", &out), 0);
  EXPECT_NE(out.find("position-dependent-friction"), std::string::npos);
}

// measurement check on a hand-written file: 1 kHz with one 51 ms hole, every other sample
// pressing 1 N; what it reports is computed here from how the file was written.
TEST(WorkbenchCli, MeasurementCheckCountsSamplesGapsAndContact) {
  test::TempDir dir;
  std::string csv =
      "# hapticlab-measurement v1\n# material: cork\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,"
      "fy_N,fz_N\n";
  int rows = 0, contact = 0;
  for (int k = 0; k < 2000; ++k) {
    if (k >= 1000 && k < 1050) continue;  // the hole: t = 0.999 -> 1.050
    const double t = k * 1e-3;
    const bool touch = rows % 2 == 0;
    csv += std::to_string(t) + "," + std::to_string(0.01 * t) + ",0,-0.0002,0.01,0,0,-0.3,0," +
           (touch ? "1" : "0") + "\n";
    ++rows;
    contact += touch;
  }
  test::WriteFile(dir.File("m.csv"), csv);
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " measurement check --json " + dir.File("m.csv"), &out), 0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["material"], "cork");
  EXPECT_EQ(j["samples"], rows);
  EXPECT_NEAR(j["duration_s"].get<double>(), 1.999, 1e-9);
  EXPECT_NEAR(j["rate_hz"].get<double>(), 1000, 1e-6);
  EXPECT_EQ(j["gaps"], 1);
  EXPECT_NEAR(j["max_gap_s"].get<double>(), 0.051, 1e-9);
  EXPECT_EQ(j["contact_samples"], contact);
  EXPECT_FALSE(j["has_acceleration"].get<bool>());
  EXPECT_NEAR(j["ranges"]["x_m"][1].get<double>(), 0.01 * 1.999, 1e-9);
  EXPECT_EQ(j["ranges"]["fz_N"], nlohmann::json::array({0.0, 1.0}));
  // The hole is named by the line of the row after it (3 header lines, 1000 rows before it).
  bool named = false, no_acc = false;
  for (const auto& w : j["warnings"]) {
    named |= w.get<std::string>().rfind("line 1004: gap of 0.051 s", 0) == 0;
    no_acc |= w.get<std::string>().find("no acc_mps2 column") != std::string::npos;
  }
  EXPECT_TRUE(named) << j["warnings"].dump();
  EXPECT_TRUE(no_acc) << j["warnings"].dump();
}

// measurement simulate is reproducible from its seed (recorded in the file); effects lists each
// catalogue entry once, and what an effect requires is in the catalogue.
TEST(WorkbenchCli, SimulateIsReproducibleAndEffectsListTheCatalogueOnce) {
  test::TempDir dir;
  std::string out;
  for (const char* f : {"a.csv", "b.csv"})
    ASSERT_EQ(test::RunCommand(
                  Cli() + " measurement simulate --duration 5 --seed 7 -o " + dir.File(f), &out),
              0)
        << out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " measurement simulate --duration 5 --seed 8 --add stribeck -o " +
                           dir.File("c.csv"),
                       &out),
      0)
      << out;
  const auto a = test::ReadFile(dir.File("a.csv")), c = test::ReadFile(dir.File("c.csv"));
  EXPECT_EQ(a, test::ReadFile(dir.File("b.csv")));
  EXPECT_NE(a.find("\n# seed: 7\n"), std::string::npos);
  EXPECT_NE(c.find("\n# seed: 8\n"), std::string::npos);
  EXPECT_NE(c.find("stribeck"), std::string::npos) << "the truth's effects are recorded";
  EXPECT_NE(a.substr(a.find("\nt_s")), c.substr(c.find("\nt_s")));
  const auto check = Json(Cli() + " measurement check --json " + dir.File("a.csv"));
  EXPECT_EQ(check["samples"], 10000);  // 5 s at the default 2 kHz
  const auto fx = Json(Cli() + " effects --json");
  std::set<std::string> names;
  for (const auto& e : fx) EXPECT_TRUE(names.insert(e["name"].get<std::string>()).second) << e;
  for (const auto& e : fx) {
    EXPECT_TRUE(std::set<std::string>({"friction", "normal_force", "vibration"})
                    .count(e["channel"].get<std::string>()))
        << e;
    for (const auto& r : e["requires"]) EXPECT_TRUE(names.count(r.get<std::string>())) << e;
  }
  ASSERT_EQ(test::RunCommand(Cli() + " effects", &out), 0);
  for (const char* b : {"coulomb", "viscous", "dahl", "hc-damping", "hc-exponent",
                        "vibration-speed", "vibration-force"}) {
    EXPECT_TRUE(names.count(b)) << b;
    EXPECT_NE(out.find(b), std::string::npos) << b;
  }
}

}  // namespace
}  // namespace hapticlab::cmd_workbench_test
