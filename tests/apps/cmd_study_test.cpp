// hapticlab study (validate, plan, run, resume, status) through the command line

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_study_test {
namespace {

using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

TEST(StudyCli, ValidateAndPlan) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + Small(), &out), 0) << out;
  EXPECT_NE(out.find("ok"), std::string::npos);
  std::string a, b;
  ASSERT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --index 5 --json", &a), 0) << a;
  ASSERT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --index 5 --json", &b), 0);
  EXPECT_EQ(a, b);  // deterministic
  EXPECT_EQ(json::parse(a)["trials"].size(), 26u);
  test::TempDir dir;
  std::string bad = test::ReadFile(Small());
  const std::string from = "algorithm = \"fric2\"";
  bad.replace(bad.find(from), from.size(), "algorithm = \"fric3\"");
  test::WriteFile(dir.File("bad.toml"), bad);
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + dir.File("bad.toml"), &out), 2);
  EXPECT_NE(out.find("bad.toml:"), std::string::npos) << out;
  EXPECT_NE(out.find("method[0].algorithm"), std::string::npos) << out;
  // A negative plan index is refused in a line, not with a 300-digit bound.
  EXPECT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --index -1", &out), 2);
  EXPECT_NE(out.find("--index"), std::string::npos) << out;
  EXPECT_LT(out.size(), 200u) << out;
}

TEST(StudyCli, RunStopResumeStatusAnalyzeExport) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  // A stopped session exits 3 (docs/studies.md), with what it completed recorded.
  ASSERT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + db +
                                 " --participant P01 --quiet --stop-after 9",
                             &out),
            3)
      << out;
  EXPECT_NE(out.find("continue with 'hapticlab study resume --db " + db + " --participant P01'"),
            std::string::npos)
      << out;
  ASSERT_EQ(test::RunCommand(Cli() + " study status --db " + db + " --json", &out), 0) << out;
  auto st = json::parse(out)["participants"][0];
  EXPECT_EQ(st["code"], "P01");
  EXPECT_EQ(st["completed"], 9);
  EXPECT_EQ(st["planned"], 26);
  EXPECT_EQ(st["duplicates"], 0);
  for (const char* k : {"code", "planned", "completed", "faulted", "duplicates"})
    EXPECT_TRUE(st.contains(k)) << k;
  ASSERT_EQ(
      test::RunCommand(Cli() + " study resume --db " + db + " --participant P01 --quiet", &out), 0)
      << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " study run " + Small() + " --db " + db + " --participant P02 --quiet", &out),
      0)
      << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " study run " + Small() + " --db " + db + " --participant P03 --quiet", &out),
      0)
      << out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " study status --db " + db + " --participant P01 --json", &out), 0)
      << out;
  EXPECT_EQ(json::parse(out)["participants"][0]["completed"], 26);
  // Running an existing participant again, or with a name, is refused with exit code 2.
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " study run " + Small() + " --db " + db + " --participant P01 --quiet", &out),
      2);
  EXPECT_NE(out.find("already completed"), std::string::npos) << out;
  // Resuming it, in another mode too, says that it is completed (not that the mode differs).
  EXPECT_EQ(test::RunCommand(
                Cli() + " study resume --db " + db + " --participant P01 --device falcon", &out),
            2);
  EXPECT_NE(out.find("already completed"), std::string::npos) << out;
  // A report or an export over a file that is not a folder: exit 2 naming --out.
  for (const std::string& cmd :
       {" analyze --db " + db + " --out " + Small(), " export --db " + db + " --out " + Small()}) {
    EXPECT_EQ(test::RunCommand(Cli() + cmd, &out), 2) << cmd;
    EXPECT_NE(out.find("--out: exists and is not a folder"), std::string::npos) << out;
  }
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " study run " + Small() + " --db " + db + " --participant Alice --quiet", &out),
      2);
  EXPECT_NE(out.find("pseudonymous"), std::string::npos) << out;
  // The analysis report.
  ASSERT_EQ(test::RunCommand(
                Cli() + " analyze --db " + db + " --out " + dir.File("rep") + " --json", &out),
            0)
      << out;
  const auto r = json::parse(out);
  EXPECT_TRUE(std::filesystem::exists(r["report"].get<std::string>()));
  int png = 0, svg = 0, pdf = 0;
  for (const auto& f : r["files"]) {
    const std::string p = f;
    if (p.ends_with(".png") || p.ends_with(".svg") || p.ends_with(".pdf")) {
      ASSERT_GT(std::filesystem::file_size(p), 1000u) << p;
    }
    png += p.ends_with(".png");
    svg += p.ends_with(".svg");
    pdf += p.ends_with(".pdf");
  }
  EXPECT_GT(png, 0);
  EXPECT_EQ(png, svg);
  EXPECT_EQ(png, pdf);
  const auto md = test::ReadFile(r["report"].get<std::string>());
  EXPECT_NE(md.find("Repeated-measures ANOVA"), std::string::npos);
  EXPECT_NE(md.find("Tukey HSD on method"), std::string::npos);
  EXPECT_NE(md.find("Real-real limits"), std::string::npos);
  const auto agg = ReadCsv(dir.File("rep/test-small_aggregate.csv"));
  EXPECT_EQ(agg.rows.size(), 2u * 4u * 2u);  // criteria x materials x methods
  // Export round trip of the ratings count.
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("x") + " --no-trajectories", &out),
      0)
      << out;
  const auto ratings = ReadCsv(dir.File("x/ratings.csv"));
  EXPECT_EQ(ratings.rows.size(), 3u * 22u * 2u);  // participants x rated trials x criteria
}

TEST(StudyCli, WindowsAndDevicesAreCheckedBeforeAnythingIsRecorded) {
  test::TempDir dir;
  std::string out;
  // No display: a clear error, and no database created.
  EXPECT_EQ(test::RunCommand("env -u DISPLAY " + Cli() + " study run " + Small() + " --db " +
                                 dir.File("a.db") + " --participant P01 --ui",
                             &out),
            1);
  EXPECT_NE(out.find("no display"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("a.db")));
  // Hardware without its inputs: named errors.
  EXPECT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + dir.File("b.db") +
                                 " --participant P01 --device falcon --ui",
                             &out),
            2);
  EXPECT_NE(out.find("--firmware"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + dir.File("b.db") +
                                 " --participant P01 --device dhd --ui",
                             &out),
            2);
  EXPECT_NE(out.find("SDK"), std::string::npos) << out;
  // Headless on hardware: refused before any device opens, naming the window and, as a
  // person takes part, the experimenter who confirmed consent.
  EXPECT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + dir.File("b.db") +
                                 " --participant P01 --device falcon",
                             &out),
            2);
  EXPECT_NE(out.find("--ui"), std::string::npos) << out;
  EXPECT_NE(out.find("--consent-confirmed-by"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + dir.File("b.db") +
                                 " --participant P01 --device falcon --consent-confirmed-by E01",
                             &out),
            2);
  EXPECT_EQ(out.find("--consent-confirmed-by"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("b.db")));
  // With a display (Xvfb), the windows open and the session runs (the first trials are
  // unrated training, so no one needs to click).
  if (test::RunCommand("command -v xvfb-run") == 0) {
    // (Leak checking off for this child under ASan: Mesa's unloaded driver, see
    // tests/CMakeLists.txt.)
    // (with_display.sh: xvfb-run's own clean-up failures must not replace the exit status.)
    ASSERT_EQ(test::RunCommand("ASAN_OPTIONS=detect_leaks=0 " + std::string(HL_SOURCE_DIR) +
                                   "/tests/util/with_display.sh " + Cli() + " study run " +
                                   Small() + " --db " + dir.File("c.db") +
                                   " --participant P01 --ui --stop-after 3 --quiet "
                                   "--consent-confirmed-by E01",
                               &out),
              3)
        << out;
    EXPECT_TRUE(std::filesystem::exists(dir.File("c.db")));
  }
}

}  // namespace
}  // namespace hapticlab::cmd_study_test
