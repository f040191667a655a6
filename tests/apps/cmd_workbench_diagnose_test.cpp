// hapticlab diagnose through the command line (apps/hapticlab/cmd_workbench_diagnose.cpp): its
// input checks. A diagnosis fits every candidate effect (seconds per candidate), so what it
// reports is asserted once, on the worked example (WorkbenchCli.FromRawMeasurementToImprovedModel
// in cmd_workbench_test.cpp: the hidden effect ranked first and supported, the ranking, the
// unexplained report's keys), and the engine in tests/modeling/workbench_diagnose_test.cpp.

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_workbench_diagnose_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(WorkbenchDiagnoseCli, BadModelOrMeasurementIsBadInputNamingFileLineAndField) {
  test::TempDir dir;
  std::string out;
  // Every problem of the model at once, each with its line and key; before the measurement.
  test::WriteFile(dir.File("bad.toml"), "name = \"x\"\n[friction]\nmu_k = \"high\"\n");
  EXPECT_EQ(test::RunCommand(Cli() + " diagnose --model " + dir.File("bad.toml") +
                                 " --measurement " + dir.File("none.csv"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("bad.toml") + ":3: friction.mu_k: expected a number"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(dir.File("bad.toml") + ": contact: missing [contact] table"),
            std::string::npos)
      << out;
  // A good model and a measurement with a bad cell: the file, its line and the column.
  test::WriteFile(dir.File("m.toml"),
                  "name = \"m\"\neffects = [\"coulomb\"]\n[contact]\ntexture_K = 1000.0\n"
                  "[friction]\nkappa_N_per_m = 3000.0\nmu_k = 0.3\n");
  test::WriteFile(
      dir.File("m.csv"),
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n"
      "0,0,0,-0.001,0.01,0,0,-0.3,0,1\n0.001,0.00001,0,-0.001,0.01,0,0,-0.3,0,one\n");
  EXPECT_EQ(test::RunCommand(Cli() + " diagnose --quiet --model " + dir.File("m.toml") +
                                 " --measurement " + dir.File("m.csv"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("m.csv") + ":4"), std::string::npos) << out;
  EXPECT_NE(out.find("fz_N"), std::string::npos) << out;
  EXPECT_EQ(out.find("diagnose: refitting"), std::string::npos) << "--quiet: " << out;
  // No measurement at all.
  EXPECT_EQ(test::RunCommand(Cli() + " diagnose --model " + dir.File("m.toml") + " --measurement " +
                                 dir.File("none.csv"),
                             &out),
            2);
  EXPECT_NE(out.find(dir.File("none.csv")), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_workbench_diagnose_test
