// hapticlab db backup through the command line (apps/hapticlab/cmd_db.cpp). The copy is read
// back through a SQLite connection of its own, not the project's Database class. (A backup
// taken while `study run` writes:
// SessionCli.SigtermStopsCleanlyAndTheMainFileAloneHoldsTheRatings.)

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_db_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(DbCli, BackupOfAnOpenDatabaseHoldsEveryCommittedRowAndNeverOverwrites) {
  test::TempDir dir;
  const std::string src = dir.File("s.db"), dest = dir.File("copy.db");
  // The writer stays open while the backup runs: committed rows may still sit in s.db-wal.
  db::Database d(src);
  const auto se = test::AddStudySession(d).session;
  for (int k = 0; k < 5; ++k) {
    const auto t = d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Cork"});
    d.CompleteTrial(t, {{"overall", 40.0 + k, 1}, {"roughness", 60.0 - k, 2}});
  }
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " db backup " + src + " " + dest, &out), 0) << out;
  EXPECT_NE(out.find("backup complete"), std::string::npos) << out;
  EXPECT_EQ(test::QueryInt(dest, "SELECT count(*) FROM rating"), 10);
  EXPECT_EQ(test::QueryInt(dest, "SELECT count(*) FROM trial WHERE status = 'completed'"), 5);
  EXPECT_EQ(test::QueryInt(dest, "SELECT sum(score) FROM rating WHERE criterion = 'overall'"),
            40 + 41 + 42 + 43 + 44);
  EXPECT_EQ(test::QueryInt(dest, "SELECT count(*) FROM participant WHERE code = 'P01'"), 1);

  // DEST exists: refused as bad input naming it, and the file is left as it was.
  const auto size = std::filesystem::file_size(dest);
  d.CompleteTrial(d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Cork"}),
                  {{"overall", 50, 1}, {"roughness", 50, 2}});
  EXPECT_EQ(test::RunCommand(Cli() + " db backup " + src + " " + dest, &out), 2);
  EXPECT_NE(out.find(dest + ": DEST: already exists"), std::string::npos) << out;
  EXPECT_EQ(std::filesystem::file_size(dest), size);
  EXPECT_EQ(test::QueryInt(dest, "SELECT count(*) FROM rating"), 10);
  // No source: named, and nothing created.
  EXPECT_EQ(
      test::RunCommand(Cli() + " db backup " + dir.File("none.db") + " " + dir.File("n.db"), &out),
      2);
  EXPECT_NE(out.find(dir.File("none.db") + ": SRC: no such database file"), std::string::npos)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("n.db")));
  // A source of another kind (a protocol) is named as SRC, in plain words, exit 2.
  test::WriteFile(dir.File("p.toml"), "[study]\n");
  EXPECT_EQ(
      test::RunCommand(Cli() + " db backup " + dir.File("p.toml") + " " + dir.File("n.db"), &out),
      2);
  EXPECT_NE(out.find(dir.File("p.toml") + ": SRC: not a SQLite database"), std::string::npos)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("n.db")));
  // A destination in a folder that does not exist: exit 2, in plain words.
  EXPECT_EQ(test::RunCommand(Cli() + " db backup " + src + " " + dir.File("none/n.db"), &out), 2);
  EXPECT_NE(out.find("DEST: its folder"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_db_test
