// The command line: help on every group, exit codes, export end to end.

#include <gtest/gtest.h>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(Cli, EveryCommandGroupHasHelp) {
  for (const char* group : {"study", "model", "model render", "model energy", "model check", "model import-penn", "model fit-vibration", "model cv-vibration", "model cutoff", "compare", "diagnose", "fit", "stats", "stats rm-anova", "stats tukey", "stats kruskal", "stats shapiro", "analyze", "study validate", "study plan", "study run", "study resume", "study status",
                            "export", "demo", "participant", "participant new", "db", "db backup"}) {
    std::string out;
    EXPECT_EQ(test::RunCommand(Cli() + " " + group + " --help", &out), 0) << group << ": " << out;
    EXPECT_NE(out.find("Usage"), std::string::npos) << group;
  }
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
  EXPECT_EQ(test::RunCommand(Cli() + " export --db " + dir.File("nope.db") + " --out " +
                                 dir.File("o"), &out), 2);
  EXPECT_NE(out.find("nope.db"), std::string::npos) << out;
}

TEST(Cli, ExportWritesTables) {
  test::TempDir dir;
  {
    db::Database d(dir.File("s.db"));
    const auto st = d.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
    const auto p = d.AddParticipant({.study_id = st, .code = "P01"});
    const auto se = d.StartSession({.participant_id = p});
    const auto t = d.AddTrial({.session_id = se, .phase = "main", .material = "Cork"});
    d.CompleteTrial(t, {{"overall", 55, 1}});
  }
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " export --json --db " + dir.File("s.db") + " --out " +
                                 dir.File("o"), &out), 0) << out;
  EXPECT_NE(out.find("\"rows\": 1"), std::string::npos) << out;
  const auto csv = test::ReadFile(dir.File("o/ratings.csv"));
  EXPECT_NE(csv.find("P01"), std::string::npos);
}

}  // namespace
}  // namespace hapticlab
