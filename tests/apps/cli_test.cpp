// The command line: help and unknown options on every command of the real tree, exit
// codes, export end to end.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "app.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cli_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// Every command of the real command tree: the App the binary builds (cli::BuildApp), walked
// recursively, so a command added to the CLI is covered without editing this test.
struct Command {
  std::vector<std::string> path;
  bool extras_allowed = false;  // it, or a group above it, accepts unknown arguments
};
std::vector<Command> CommandTree() {
  CLI::App app;
  cli::BuildApp(app);
  std::vector<Command> out;
  std::function<void(CLI::App*, const Command&)> walk = [&](CLI::App* a, const Command& parent) {
    for (CLI::App* sub : a->get_subcommands([](CLI::App*) { return true; })) {
      Command c = parent;
      c.path.push_back(sub->get_name());
      c.extras_allowed = c.extras_allowed || sub->get_allow_extras();
      out.push_back(c);
      walk(sub, c);
    }
  };
  walk(&app, {.path = {}, .extras_allowed = app.get_allow_extras()});
  return out;
}

// Runs the CLI in this process (cli::RunCli, what main() runs) on `path` + `last`; stdout and
// stderr into *out.
int RunInProcess(const std::vector<std::string>& path, const std::string& last, std::string* out) {
  std::vector<std::string> args{"hapticlab"};
  args.insert(args.end(), path.begin(), path.end());
  args.push_back(last);
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int rc = cli::RunCli(static_cast<int>(argv.size()), argv.data());
  *out = testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr();
  return rc;
}

std::string Joined(const std::vector<std::string>& path) {
  std::string s;
  for (const auto& p : path) s += (s.empty() ? "" : " ") + p;
  return s;
}

TEST(Cli, EveryCommandOfTheRealTreeHasHelpAndRefusesAnUnknownOption) {
  const auto commands = CommandTree();
  std::set<std::string> names;
  for (const auto& c : commands) names.insert(Joined(c.path));
  // The walk reaches the leaves of every group (the hand list this replaces missed some).
  for (const char* leaf :
       {"model photometric", "model build", "model fit-contact", "model fit-neural", "study run",
        "study power", "study calibrate", "rig check", "db backup", "measurement check", "effects"})
    EXPECT_EQ(names.count(leaf), 1u) << leaf << " is not in the command tree";
  for (const auto& c : commands) {
    std::string out;
    EXPECT_EQ(RunInProcess(c.path, "--help", &out), 0) << Joined(c.path) << ": " << out;
    EXPECT_NE(out.find("Usage"), std::string::npos) << Joined(c.path) << ": " << out;
    // Refused: exit 2 (bad usage), and no command on the way accepts unknown arguments (a
    // command with required options may report those first).
    EXPECT_EQ(RunInProcess(c.path, "--no-such-option", &out), 2) << Joined(c.path) << ": " << out;
    EXPECT_FALSE(c.extras_allowed) << Joined(c.path) << " accepts unknown options";
  }
}

TEST(Cli, TheBinaryRunsTheSameTree) {
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " --help", &out), 0) << out;
  CLI::App app;
  cli::BuildApp(app);
  for (CLI::App* group : app.get_subcommands([](CLI::App*) { return true; }))
    EXPECT_NE(out.find(group->get_name()), std::string::npos)
        << group->get_name() << " missing from the binary's help";
}

TEST(Cli, BadUsageExitsWithTwo) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " no-such-command", &out), 2) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " export --db", &out), 2) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " export --db x.db --out o --format xml", &out), 2) << out;
  EXPECT_EQ(test::RunCommand(Cli(), &out), 2) << out;
}

TEST(Cli, ExportOfAMissingDatabaseNamesTheFileAndExitsWithTwo) {
  test::TempDir dir;
  std::string out;
  EXPECT_EQ(test::RunCommand(
                Cli() + " export --db " + dir.File("nope.db") + " --out " + dir.File("o"), &out),
            2);
  EXPECT_NE(out.find("nope.db"), std::string::npos) << out;
}

TEST(Cli, ExportWritesTables) {
  test::TempDir dir;
  {
    db::Database d(dir.File("s.db"));
    const auto se = test::AddStudySession(d).session;
    const auto t = d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Cork"});
    d.CompleteTrial(t, {{"overall", 55, 1}});
  }
  std::string out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --json --db " + dir.File("s.db") + " --out " + dir.File("o"), &out),
      0)
      << out;
  EXPECT_NE(out.find("\"rows\": 1"), std::string::npos) << out;
  const auto csv = test::ReadFile(dir.File("o/ratings.csv"));
  EXPECT_NE(csv.find("P01"), std::string::npos);
}

// Start-up (docs/performance.md, "Start-up"): OpenCV's image codecs and the ~150 libraries
// they need (GDAL, Poppler, HDF5, ...) are not loaded when the binary starts
// (apps/hapticlab/lazy_imgcodecs.cpp loads them at the first image read or write; the
// photometric command-line tests read and write images through it). The check is on the
// binary's NEEDED entries, not on a time.
TEST(Cli, ImageCodecsAreNotLoadedAtStartUp) {
  std::string needed;
  ASSERT_EQ(test::RunCommand("readelf -d " + Cli() + " | grep NEEDED", &needed), 0) << needed;
  EXPECT_EQ(needed.find("opencv_imgcodecs"), std::string::npos) << needed;
  EXPECT_EQ(needed.find("gdal"), std::string::npos) << needed;
  // The check would notice: the binary does link OpenCV's core (cv::Mat).
  EXPECT_NE(needed.find("opencv_core"), std::string::npos) << needed;
}

}  // namespace
}  // namespace hapticlab::cli_test
