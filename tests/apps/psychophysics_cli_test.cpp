// The example JND study end to end through the command line: run with --device sim, analyse,
// and find the simulated observer's true JND inside the report's bootstrap interval; a bad
// adaptive phase exits 2 naming file, line and key. Release only (scripts/test excludes it
// from the sanitizer pass: its code runs there in the psychophysics, runner and stats tests).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::psychophysics_cli_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }
std::string Example() {
  return std::string(HL_SOURCE_DIR) + "/studies/examples/vibration-gain-jnd.toml";
}

TEST(PsychophysicsCli, ExampleJndStudyRunsAndReportsTheJnd) {
  test::TempDir dir;
  const std::string db = dir.File("jnd.db");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " study validate " + Example(), &out), 0) << out;
  EXPECT_NE(out.find("1 adaptive phase"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(Cli() + " study run " + Example() + " --db " + db +
                                 " --participant P01 --device sim --record none --quiet",
                             &out),
            0)
      << out;
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + dir.File("rep"), &out), 0)
      << out;
  const std::string md = test::ReadFile(dir.File("rep/report.md"));
  EXPECT_NE(md.find("| P01 |"), std::string::npos) << md;
  EXPECT_NE(md.find("![psychometric function, phase 1]"), std::string::npos) << md;
  const CsvTable t = ReadCsv(dir.File("rep/example-vibration-gain-jnd_psychometric.csv"));
  ASSERT_EQ(t.rows.size(), 1u);
  // The observer's truth (the protocol's [phase.simulated_observer]): Weibull, threshold 0.2,
  // slope 3, lapse 0.02, 2AFC: JND (75 %) = 0.2 (-ln(1 - 0.25 / 0.48))^(1/3) = 0.1806.
  const double true_jnd = 0.2 * std::cbrt(-std::log(1 - 0.25 / 0.48));
  EXPECT_LE(t.Number(0, t.Require("jnd_lo")), true_jnd);
  EXPECT_GE(t.Number(0, t.Require("jnd_hi")), true_jnd);
  EXPECT_DOUBLE_EQ(t.Number(0, t.Require("weber")), t.Number(0, t.Require("jnd")));  // reference 1
  EXPECT_GT(t.Number(0, t.Require("staircase_estimate")), 0);
  // A bad adaptive phase: exit 2, file, line and key.
  std::string bad = test::ReadFile(Example());
  const auto at = bad.find("down = 2");
  bad.replace(at, 8, "down = 0");
  test::WriteFile(dir.File("bad.toml"), bad);
  // The line of the changed key in the example (1-based).
  const auto line =
      1 + std::count(bad.begin(), bad.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + dir.File("bad.toml"), &out), 2);
  EXPECT_NE(
      out.find("bad.toml:" + std::to_string(line) + ": phase[1].down: expected an integer 1..5"),
      std::string::npos)
      << out;
}

}  // namespace
}  // namespace hapticlab::psychophysics_cli_test
