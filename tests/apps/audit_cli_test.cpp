// The audit trail through the command line (issue 31): consent recorded as it happened, faulted
// attempts printed and counted, no host name or absolute path left in the record or a report,
// a resume whose recorded mode cannot start here refused as bad input, exit code 3 listed.
// The database is read by the test's own SQLite connection (test::QueryInt).

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>

#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::audit_cli_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }
std::string RunCmd(const std::string& db, const std::string& code, const std::string& more) {
  return Cli() + " study run " + Small() + " --db " + db + " --participant " + code + " " + more;
}

TEST(AuditCli, AHeadlessSimulatedRunRecordsConsentAsNotApplicableAndClearsTheLease) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  ASSERT_EQ(test::RunCommand(RunCmd(db, "P01", "--quiet --record none"), &out), 0) << out;
  EXPECT_EQ(test::QueryInt(db, "SELECT count(*) FROM event WHERE detail LIKE '%signed%'"), 0);
  EXPECT_EQ(test::QueryInt(db,
                           "SELECT count(*) FROM event WHERE kind = 'consent' AND detail LIKE 'not "
                           "applicable: simulated%' AND established_by = 'hapticlab:session-mode'"),
            1);
  EXPECT_EQ(test::QueryInt(db, "SELECT count(*) FROM event WHERE established_by = ''"), 0);
  EXPECT_EQ(test::QueryInt(db, "SELECT count(*) FROM writer_lease"), 0) << "the host name stayed";
  // The events export names each event's source.
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("x") + " --no-trajectories", &out),
      0)
      << out;
  const auto events = test::ReadFile(dir.File("x/events.csv"));
  EXPECT_EQ(events.rfind("study,participant,session_id,trial,kind,detail,created_at,"
                         "established_by\n",
                         0),
            0u)
      << events.substr(0, 200);
  EXPECT_NE(events.find("hapticlab:session-mode"), std::string::npos);
  // A consent code for a simulated session is refused (no person takes part).
  EXPECT_EQ(test::RunCommand(RunCmd(db, "P02", "--quiet --consent-confirmed-by E01"), &out), 2);
  EXPECT_NE(out.find("--consent-confirmed-by"), std::string::npos) << out;
}

TEST(AuditCli, FaultedAttemptsArePrintedAndCountedByStatus) {
  test::TempDir dir;
  const std::string db = dir.File("f.db");
  std::string out;
  // --quiet leaves out progress, not faults.
  ASSERT_EQ(test::RunCommand(
                RunCmd(db, "P01", "--device falcon-twin --inject-faults 0.3 --record none --quiet"),
                &out),
            0)
      << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("(\\d+) faults re-queued"))) << out;
  const int faults = std::stoi(m[1]);
  ASSERT_GT(faults, 0) << "no fault injected: the test tests nothing\n" << out;
  const std::regex line(
      "P01: trial (\\d+) \\((main|reference), attempt (\\d+)\\) faulted: "
      "[^\\n]*disconnect[^\\n]*re-queued");
  const auto lines = static_cast<int>(
      std::distance(std::sregex_iterator(out.begin(), out.end(), line), std::sregex_iterator()));
  EXPECT_EQ(lines, faults) << out;
  ASSERT_EQ(test::RunCommand(Cli() + " study status --db " + db + " --json", &out), 0) << out;
  const auto st = json::parse(out)["participants"][0];
  EXPECT_EQ(st["faulted"], faults);
  EXPECT_EQ(st["completed"], st["planned"]);
  EXPECT_EQ(test::QueryInt(db, "SELECT count(*) FROM event WHERE kind = 'attempt-faulted'"),
            faults);
  EXPECT_GE(
      test::QueryInt(db,
                     "SELECT count(*) FROM event WHERE kind = 'device-fault' AND established_by = "
                     "'simulation:inject-faults'"),
      faults);
}

TEST(AuditCli, AConsoleSessionCarriesTheExperimenterAndAResumeWithoutDisplayIsBadInput) {
  if (test::RunCommand("command -v xvfb-run") != 0) GTEST_SKIP() << "no xvfb-run";
  test::TempDir dir;
  const std::string db = dir.File("u.db");
  std::string out;
  const std::string display =
      "ASAN_OPTIONS=detect_leaks=0 " + std::string(HL_SOURCE_DIR) + "/tests/util/with_display.sh ";
  // A person takes part on hardware: headless, without an experimenter's confirmation, the
  // session does not start (with --ui and no flag the console's consent modal asks instead:
  // Screenshot.ConsentModalNamesTheDocumentAndTakesOnlyACode).
  EXPECT_EQ(test::RunCommand(RunCmd(db, "P01", "--device falcon --quiet"), &out), 2) << out;
  EXPECT_NE(out.find("--consent-confirmed-by"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(db)) << "refused before anything is written";
  EXPECT_EQ(
      test::RunCommand(
          display + RunCmd(db, "P01", "--ui --stop-after 3 --quiet --consent-confirmed-by E01"),
          &out),
      3)
      << out;
  EXPECT_EQ(
      test::QueryInt(db,
                     "SELECT count(*) FROM event WHERE kind = 'consent' AND established_by = "
                     "'experimenter:E01' AND detail LIKE '%E01 (command line)%' AND detail LIKE "
                     "'%\"test-small consent form\", version \"2026-11\"%'"),
      1);
  EXPECT_EQ(test::QueryInt(db, "SELECT count(*) FROM event WHERE detail LIKE '%signed%'"), 0);
  // Resumed in its recorded mode (screens on) where there is no display: bad input naming
  // both the recorded mode and the one that could start, not a GLFW failure.
  EXPECT_EQ(test::RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + Cli() + " study resume --db " +
                                 db + " --participant P01 --quiet",
                             &out),
            2)
      << out;
  EXPECT_NE(out.find("screens on"), std::string::npos) << out;
  EXPECT_NE(out.find("screens off"), std::string::npos) << out;
  EXPECT_NE(out.find("--change-mode"), std::string::npos) << out;
}

TEST(AuditCli, HelpListsExitCodeThreeAndReportsHoldNoAbsolutePath) {
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " --help", &out), 0) << out;
  EXPECT_TRUE(std::regex_search(out, std::regex("Exit codes:[\\s\\S]*3 'study run'"))) << out;
  test::TempDir dir;
  const std::string db = fs::absolute(dir.File("s.db")).string();
  for (const char* p : {"P01", "P02"})
    ASSERT_EQ(test::RunCommand(RunCmd(db, p, "--quiet --record none"), &out), 0) << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " analyze --db " + db + " --out " + dir.File("rep") + " --no-figures", &out),
      0)
      << out;
  int files = 0;
  for (const auto& f : fs::recursive_directory_iterator(dir.File("rep"))) {
    if (!f.is_regular_file()) continue;
    ++files;
    const auto text = test::ReadFile(f.path().string());
    EXPECT_EQ(text.find(dir.path()), std::string::npos) << f.path() << " names the folder";
  }
  EXPECT_GT(files, 1);
  EXPECT_NE(test::ReadFile(dir.File("rep/report.md")).find("Database: `s.db`"), std::string::npos);
}

}  // namespace
}  // namespace hapticlab::audit_cli_test
