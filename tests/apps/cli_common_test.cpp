// The command line's shared scaffolding (apps/hapticlab/cli_common.cpp), in this process: the
// exception -> exit code map of docs/architecture.md "Errors", library field names shown as
// the flags that set them, parse exit codes, --json output, the progress log.

#include "cli_common.hpp"

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::cli_common_test {
namespace {

// Runs `body` under cli::Guard; stderr into *err.
int Guarded(const std::function<int()>& body, std::string* err) {
  testing::internal::CaptureStderr();
  const int rc = cli::Guard(body);
  *err = testing::internal::GetCapturedStderr();
  return rc;
}

TEST(CliCommon, GuardMapsEachKindOfErrorToItsExitCode) {
  std::string err;
  EXPECT_EQ(Guarded([] { return 0; }, &err), cli::kExitOk);
  EXPECT_EQ(err, "");
  EXPECT_EQ(Guarded([] { return 3; }, &err), 3);  // a command's own code passes through
  // Bad user data: exit 2 with the message (file, line, field) as the library wrote it.
  EXPECT_EQ(Guarded([]() -> int { throw InputError("m.csv", 7, "fz_N", "not a number"); }, &err),
            cli::kExitBadInput);
  EXPECT_EQ(err, "error: m.csv:7: fz_N: not a number\n");
  // API misuse is a programming error, not bad input: exit 1, asking for a report.
  EXPECT_EQ(Guarded([]() -> int { HL_REQUIRE(1 + 1 == 3, "arithmetic"); }, &err),
            cli::kExitFailure);
  EXPECT_NE(err.find("internal error (please report)"), std::string::npos) << err;
  EXPECT_NE(err.find("arithmetic"), std::string::npos) << err;
  // The environment failing (I/O, a diverged fit): exit 1.
  EXPECT_EQ(Guarded([]() -> int { throw std::runtime_error("disk full"); }, &err),
            cli::kExitFailure);
  EXPECT_EQ(err, "failed: disk full\n");
  // Data a library computation cannot use (it names the data, not a file): bad input, exit 2.
  EXPECT_EQ(
      Guarded([]() -> int { throw InputError("", 0, "samples", "the recording is constant"); },
              &err),
      cli::kExitBadInput);
  EXPECT_EQ(err, "error: samples: the recording is constant\n");
  // The "Transitional" branch is gone: std::invalid_argument is library text, not bad input.
  EXPECT_EQ(Guarded([]() -> int { throw std::invalid_argument("bad k"); }, &err),
            cli::kExitFailure);
}

TEST(CliCommon, WithFlagsNamesTheFlagsThatSetTheFieldsAndKeepsEverythingElse) {
  Diagnostics d;
  d.Add("<command line>", 0, "db", "no such database file");
  d.Add("p.toml", 4, "participant_code", "expected a pattern");
  d.Add("q.toml", 9, "dbx", "unrelated field");
  try {
    cli::WithFlags({{"db", "--db"}, {"participant_code", "--participant"}},
                   [&] { d.ThrowIfAny(); });
    FAIL() << "WithFlags swallowed the error";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 3u);
    EXPECT_EQ(e.diagnostics()[0].field, "--db");
    EXPECT_EQ(e.diagnostics()[1].field, "--participant");
    EXPECT_EQ(e.diagnostics()[1].file, "p.toml");
    EXPECT_EQ(e.diagnostics()[1].line, 4);
    EXPECT_EQ(e.diagnostics()[1].message, "expected a pattern");
    EXPECT_EQ(e.diagnostics()[2].field, "dbx");  // only whole field names are replaced
  }
  // Other exceptions pass through untouched; no exception, no change.
  EXPECT_THROW(cli::WithFlags({{"db", "--db"}}, [] { throw std::runtime_error("io"); }),
               std::runtime_error);
  int ran = 0;
  cli::WithFlags({}, [&] { ++ran; });
  EXPECT_EQ(ran, 1);
}

// A one-command app as the commands build theirs.
int Parse(const std::vector<std::string>& args, const std::function<int()>& body,
          std::string* out) {
  CLI::App app;
  app.require_subcommand(1);
  auto* cmd = app.add_subcommand("go", "Run the body");
  std::string db;
  cmd->add_option("--db", db, "A database")->required();
  cmd->callback([&] { cli::RunGuarded({{"db", "--db"}}, body); });
  std::vector<const char*> argv{"hapticlab"};
  for (const auto& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int rc = cli::ParseAndRun(app, static_cast<int>(argv.size()), argv.data());
  *out = testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr();
  return rc;
}

TEST(CliCommon, ParseAndRunReturnsTheCommandsCodeOrTwoForBadUsage) {
  std::string out;
  auto ok = [] { return cli::kExitOk; };
  EXPECT_EQ(Parse({"go", "--db", "x.db"}, ok, &out), 0) << out;
  EXPECT_EQ(Parse(
                {"go", "--db", "x.db"}, [] { return cli::kExitStopped; }, &out),
            3);
  EXPECT_EQ(Parse({"--help"}, ok, &out), 0);
  EXPECT_NE(out.find("Usage"), std::string::npos) << out;
  EXPECT_EQ(Parse({"go"}, ok, &out), 2) << "a required option missing";
  EXPECT_EQ(Parse({"go", "--db", "x.db", "--nope"}, ok, &out), 2);
  EXPECT_EQ(Parse({"stop"}, ok, &out), 2);
  // The body's InputError about a field reaches the user as the flag, with exit 2.
  EXPECT_EQ(Parse(
                {"go", "--db", "x.db"},
                []() -> int { throw InputError("x.db", 0, "db", "no such database file"); }, &out),
            2);
  EXPECT_NE(out.find("error: x.db: --db: no such database file"), std::string::npos) << out;
}

// A named-value option (--record, --actuator): CLI11 checks the name against the table, --help
// lists the names in table order with the default's name, and the value arrives parsed.
enum class Speed { kSlow, kFast, kOff };
inline constexpr EnumTable<Speed, 3> kSpeedNames{
    {{Speed::kFast, "fast"}, {Speed::kSlow, "slow"}, {Speed::kOff, "off"}}};

TEST(CliCommon, EnumOptionsTakeTheTablesNamesAndListThemInHelp) {
  for (const auto& [arg, want] : std::vector<std::pair<std::string, Speed>>{
           {"", Speed::kSlow}, {"fast", Speed::kFast}, {"off", Speed::kOff}}) {
    CLI::App app("t");
    Speed speed = Speed::kSlow;
    cli::AddEnumOption(&app, "--speed", speed, kSpeedNames, "How fast");
    std::vector<const char*> argv{"t"};
    if (!arg.empty()) argv.insert(argv.end(), {"--speed", arg.c_str()});
    std::string out;
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    const int rc = cli::ParseAndRun(app, static_cast<int>(argv.size()), argv.data());
    out = testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 0) << out;
    EXPECT_EQ(speed, want) << arg;
  }
  CLI::App app("t");
  Speed speed = Speed::kOff;
  cli::AddEnumOption(&app, "--speed", speed, kSpeedNames, "How fast");
  EXPECT_NE(app.help().find("--speed TEXT:{fast,slow,off}=off"), std::string::npos) << app.help();
  for (const char* bad : {"Fast", "medium", ""}) {
    const std::vector<const char*> argv{"t", "--speed", bad};
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    const int rc = cli::ParseAndRun(app, 3, argv.data());
    const std::string out =
        testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, cli::kExitBadInput) << bad;
    EXPECT_NE(out.find("{fast,slow,off}"), std::string::npos) << out;
    EXPECT_EQ(speed, Speed::kOff) << "a refused name leaves the value";
  }
}

TEST(CliCommon, PrintJsonStderrLogAndPlannedCommands) {
  testing::internal::CaptureStdout();
  cli::PrintJson(nlohmann::json{{"a", 1}});
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "{\n  \"a\": 1\n}\n");
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  cli::StderrLog(false)("fitting");
  cli::StderrLog(true)("hidden");
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");  // progress never mixes into stdout
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "fitting\n");
  // A planned command says which issue brings it, and the work failed (exit 1), whatever its
  // arguments.
  CLI::App app;
  cli::AddPlanned(app, "later", "Something", "issue 99");
  const char* argv[] = {"hapticlab", "later", "--any", "thing"};
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::ParseAndRun(app, 4, argv), cli::kExitFailure);
  EXPECT_NE(
      testing::internal::GetCapturedStderr().find("not available in this build yet (issue 99)"),
      std::string::npos);
}

}  // namespace
}  // namespace hapticlab::cli_common_test
