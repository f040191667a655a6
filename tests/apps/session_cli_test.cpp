// The experimenter's and analyst's workflow through the command line (issue 17): session
// mode and rating source, resume in the recorded mode, simulated ratings kept out of a human
// study, stats over the project's own export, validate as strict as run, plan numbering.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::session_cli_test {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

// Events of a kind in the database (read through the library).
int CountEvents(const std::string& db_path, db::EventKind kind) {
  db::Database d(db_path, {.create = false, .read_only = true});
  int n = 0;
  for (const auto& st : d.Studies())
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id))
        for (const auto& e : d.Events(se.id)) n += e.kind == kind;
  return n;
}

// A run stopped on purpose (--stop-after) ends 'aborted'. Its exit status is the one
// documented for a stopped session (docs/studies.md), so the record is checked instead.
void RunStopped(const std::string& command) {
  std::string out;
  const int rc = test::RunCommand(command, &out);
  EXPECT_NE(rc, 2) << out;
  EXPECT_NE(out.find(" aborted "), std::string::npos) << rc << ": " << out;
}

TEST(SessionCli, ResumeContinuesInTheRecordedModeAndRefusesAnotherUnlessTold) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  RunStopped(Cli() + " study run " + Small() + " --db " + db +
             " --participant P01 --quiet --stop-after 6");
  // Another back-end, or the screens, is refused before anything opens, naming both modes.
  EXPECT_EQ(test::RunCommand(Cli() + " study resume --db " + db +
                                 " --participant P01 --quiet --device falcon-twin",
                             &out),
            2);
  EXPECT_NE(
      out.find("recorded in mode [device sim, actuator none, screens off, ratings simulated]"),
      std::string::npos)
      << out;
  EXPECT_NE(out.find("--change-mode"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand("env -u DISPLAY " + Cli() + " study resume --db " + db +
                                 " --participant P01 --quiet --ui",
                             &out),
            2);
  EXPECT_NE(out.find("screens on"), std::string::npos) << out;
  EXPECT_EQ(CountEvents(db, db::EventKind::kModeChange), 0);
  // Told explicitly: continues in the new mode and logs the change.
  RunStopped(Cli() + " study resume --db " + db +
             " --participant P01 --quiet --device falcon-twin --change-mode "
             "--stop-after 1");
  EXPECT_EQ(CountEvents(db, db::EventKind::kModeChange), 1);
  {
    db::Database d(db, {.create = false, .read_only = true});
    EXPECT_EQ(d.Sessions(1).at(0).device, "falcon-twin");
  }
  // With no options, resume continues in the (new) recorded mode.
  RunStopped(Cli() + " study resume --db " + db + " --participant P01 --quiet --stop-after 2");
  EXPECT_EQ(CountEvents(db, db::EventKind::kModeChange), 1);
  EXPECT_EQ(CountEvents(db, db::EventKind::kResume), 2);
  // Every exported rating names its source.
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("x") + " --no-trajectories", &out),
      0)
      << out;
  const auto ratings = ReadCsv(dir.File("x/ratings.csv"));
  const auto src = ratings.Require("source");
  ASSERT_FALSE(ratings.rows.empty());
  for (const auto& r : ratings.rows) EXPECT_EQ(r[src], "simulated");
}

// The project's own export of a study with a reference phase (empty method cells in its
// real-real rows) goes through stats with --where phase=main and gives the F of the report.
// Then two participants' ratings are marked as given in the participant window (as the window
// stores them) next to one simulated session: the analysis and the stats over the export
// leave the simulated ratings out unless asked, and say so.
TEST(SessionCli, StatsReadTheOwnExportAndSimulatedRatingsStayOutOfAHumanStudy) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  for (const char* p : {"P01", "P02", "P03"})
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + db + " --participant " +
                                   p + " --quiet --record none",
                               &out),
              0)
        << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("x") + " --no-trajectories", &out),
      0)
      << out;
  std::string csv = dir.File("x/ratings.csv");
  std::string common = " --csv " + csv + " --dv score --where criterion=overall";
  // Without the filter the reference rows' empty method cells are still an error, named.
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " stats rm-anova" + common + " --subject participant --within method", &out),
      2);
  EXPECT_NE(out.find("method: empty key cell"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(
                Cli() + " stats rm-anova" + common +
                    " --where phase=main --subject participant --within method,material --json",
                &out),
            0)
      << out;
  const auto anova = json::parse(out);
  ASSERT_EQ(test::RunCommand(Cli() + " stats tukey" + common +
                                 " --where phase=main --subject participant --within "
                                 "method,material --factor method --json",
                             &out),
            0)
      << out;
  EXPECT_FALSE(json::parse(out).empty());
  // The same F as the report computes from the database.
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + dir.File("rep") +
                                 " --no-figures --json",
                             &out),
            0)
      << out;
  auto md = test::ReadFile(json::parse(out)["report"].get<std::string>());
  EXPECT_NE(md.find("All ratings come from the simulated observer"), std::string::npos) << md;
  const auto rep = ReadCsv(dir.File("rep/test-small_overall_rmanova.csv"));
  int compared = 0;
  for (const auto& row : rep.rows)
    for (const auto& e : anova["effects"])
      if (e["effect"] == row[rep.Require("effect")]) {
        EXPECT_NEAR(e["F"].get<double>(), std::stod(row[rep.Require("F")]),
                    1e-6 * e["F"].get<double>())
            << row[0];
        ++compared;
      }
  EXPECT_EQ(compared, 3);  // method, material, method:material

  // P01 and P02 rated by people, P03 simulated.
  {
    db::Database d(db);
    d.Exec(
        "UPDATE rating SET source = 'window' WHERE trial_id IN (SELECT t.id FROM trial t JOIN "
        "session s ON "
        "s.id = t.session_id JOIN participant p ON p.id = s.participant_id WHERE p.code IN "
        "('P01','P02'))");
  }
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + dir.File("rep1") +
                                 " --no-figures --json",
                             &out),
            0)
      << out;
  md = test::ReadFile(json::parse(out)["report"].get<std::string>());
  EXPECT_NE(md.find("Participants: 2; ratings: 88"), std::string::npos)
      << md;  // 2 x 22 rated trials x 2 criteria
  EXPECT_NE(md.find("**Simulated ratings excluded:** 44 ratings"), std::string::npos) << md;
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + dir.File("rep2") +
                                 " --no-figures --include-simulated --json",
                             &out),
            0)
      << out;
  md = test::ReadFile(json::parse(out)["report"].get<std::string>());
  EXPECT_NE(md.find("Participants: 3; ratings: 132"), std::string::npos) << md;
  EXPECT_NE(md.find("**Simulated ratings included**"), std::string::npos) << md;
  // The export carries the source; stats over it leave the simulated rows out with a note.
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("y") + " --no-trajectories", &out),
      0)
      << out;
  const std::string stats =
      Cli() + " stats rm-anova --csv " + dir.File("y/ratings.csv") +
      " --dv score --subject participant --within method,material --where phase=main "
      "--where criterion=overall --json";
  // The JSON on stdout (to a file), the note on stderr.
  ASSERT_EQ(test::RunCommand("{ " + stats + " > " + dir.File("a.json") + "; }", &out), 0) << out;
  EXPECT_NE(
      out.find("44 rows rated by the simulated observer are left out (88 rated by participants)"),
      std::string::npos)
      << out;
  EXPECT_EQ(json::parse(test::ReadFile(dir.File("a.json")))["subjects"], 2);
  ASSERT_EQ(test::RunCommand(stats + " --include-simulated", &out), 0) << out;
  EXPECT_EQ(json::parse(out)["subjects"], 3) << out;
}

// `study validate` finds what `study run` would refuse, naming the file looked up.
TEST(SessionCli, ValidateRunsTheChecksOfRun) {
  test::TempDir dir;
  fs::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("profiles.toml"));
  const std::string small = test::ReadFile(Small());
  auto variant = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string t = small;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    test::WriteFile(dir.File(name), t);
    return dir.File(name);
  };
  std::string out;
  ASSERT_EQ(test::RunCommand(
                Cli() + " study validate " + variant("ok.toml", "seed = 42", "seed = 42"), &out),
            0)
      << out;
  // A profiles file that does not exist: the path looked up is named.
  const auto missing =
      variant("missing.toml", "profiles = \"profiles.toml\"", "profiles = \"nope.toml\"");
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + missing, &out), 2);
  EXPECT_NE(out.find("study.profiles"), std::string::npos) << out;
  EXPECT_NE(out.find(dir.File("nope.toml")), std::string::npos) << out;
  // A material whose profile the profiles file lacks.
  const auto noprof =
      variant("noprof.toml", "id = \"Cork\"", "id = \"Cork\"\nprofile = \"Velvet\"");
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + noprof, &out), 2);
  EXPECT_NE(out.find("noprof.toml:"), std::string::npos) << out;
  EXPECT_NE(out.find("no profile 'Velvet'"), std::string::npos) << out;
  // A model file that does not exist.
  const auto nomodel =
      variant("nomodel.toml", "id = \"Towel\"", "id = \"Towel\"\nmodel = \"models/towel.toml\"");
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + nomodel, &out), 2);
  EXPECT_NE(out.find("no model file 'models/towel.toml'"), std::string::npos) << out;
  // run refuses the same protocols, before creating the database.
  EXPECT_EQ(test::RunCommand(
                Cli() + " study run " + noprof + " --db " + dir.File("n.db") + " --participant P01",
                &out),
            2);
  EXPECT_FALSE(fs::exists(dir.File("n.db")));
  // A pair naming an unknown material: the message names it.
  const auto pair =
      variant("pair.toml", "different_pairs = 2", "different_pairs = [[\"Denim\", \"Silk\"]]");
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + pair, &out), 2);
  EXPECT_NE(out.find("unknown material id 'Silk'"), std::string::npos) << out;
}

// Trials are numbered from 1 in `study plan` as everywhere else; --participant is a code
// (looked up in --db), --index a plan index.
TEST(SessionCli, PlanNumbersTrialsFromOneAndTakesACodeOrAnIndex) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --index 1 --json", &out), 0)
      << out;
  const auto by_index = json::parse(out);
  EXPECT_EQ(by_index["trials"][0]["trial"], 1);
  EXPECT_EQ(by_index["trials"][0]["plan_index"], 0);
  ASSERT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --index 1", &out), 0) << out;
  EXPECT_NE(out.find("\n   1  training"), std::string::npos) << out;
  EXPECT_EQ(out.find("\n   0  "), std::string::npos) << out;
  // A code needs the database that gave it its index.
  EXPECT_EQ(test::RunCommand(Cli() + " study plan " + Small() + " --participant P07", &out), 2);
  EXPECT_NE(out.find("--db"), std::string::npos) << out;
  RunStopped(Cli() + " study run " + Small() + " --db " + db +
             " --participant P07 --index 1 --quiet --stop-after 0");
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " study plan " + Small() + " --participant P07 --db " + db + " --json", &out),
      0)
      << out;
  EXPECT_EQ(json::parse(out), by_index);
  EXPECT_EQ(
      test::RunCommand(Cli() + " study plan " + Small() + " --participant P08 --db " + db, &out),
      2);
  EXPECT_NE(out.find("no participant P08"), std::string::npos) << out;
}

// SIGTERM to a running `study run`: the session stops at the next trial boundary, ends
// 'aborted' with an 'interrupted' event and checkpoints, so the database file copied alone
// (without its -wal) holds every committed rating. `db backup` of the live database is a
// complete, consistent copy.
TEST(SessionCli, SigtermStopsCleanlyAndTheMainFileAloneHoldsTheRatings) {
  test::TempDir dir;
  fs::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("profiles.toml"));
  std::string text = test::ReadFile(Small());
  text.replace(text.find("repetitions = 2"), 15,
               "repetitions = 40");  // 320 main trials: still running
  test::WriteFile(dir.File("long.toml"), text);
  const std::string db = dir.File("s.db");
  const std::string cli = Cli(), proto = dir.File("long.toml");
  std::vector<std::string> args{cli, "study",         "run", proto,    "--db",
                                db,  "--participant", "P01", "--quiet"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, dir.File("out.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, dir.File("err.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, cli.c_str(), &fa, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  // Wait (bounded) until a few trials are rated.
  const std::string rated = "SELECT count(*) FROM rating";
  int status = 0;
  bool exited = false;
  for (int i = 0; i < 6000 && test::TryQueryInt(db, rated).value_or(-1) < 6; ++i) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_FALSE(exited) << test::ReadFile(dir.File("err.txt"));
  ASSERT_GE(test::QueryInt(db, rated), 6);
  // An online backup while the session writes: whole (every completed rated trial has both
  // criteria) and at least what was committed before it began.
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " db backup " + db + " " + dir.File("b.db"), &out), 0) << out;
  EXPECT_GE(test::QueryInt(dir.File("b.db"), rated), 6);
  EXPECT_EQ(
      test::QueryInt(dir.File("b.db"), rated),
      2 * test::QueryInt(
              dir.File("b.db"),
              "SELECT count(*) FROM trial WHERE status = 'completed' AND phase <> 'training'"));
  EXPECT_NE(test::RunCommand(Cli() + " db backup " + db + " " + dir.File("b.db"), &out),
            0);  // never overwrites
  EXPECT_NE(out.find("already exists"), std::string::npos) << out;
  // SIGTERM: a clean stop, not death by the signal.
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal "
                                 << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_NE(test::ReadFile(dir.File("out.txt")).find(" aborted "), std::string::npos)
      << test::ReadFile(dir.File("out.txt"));
  // The main file alone, copied without -wal, holds every committed rating.
  fs::copy_file(db, dir.File("alone.db"));
  const int committed = test::QueryInt(db, rated);
  EXPECT_GT(committed, 6);
  EXPECT_EQ(test::QueryInt(dir.File("alone.db"), rated), committed);
  EXPECT_EQ(
      test::QueryInt(dir.File("alone.db"), "SELECT count(*) FROM event WHERE kind = 'interrupted'"),
      1);
  EXPECT_EQ(
      test::QueryInt(dir.File("alone.db"), "SELECT count(*) FROM session WHERE status = 'aborted'"),
      1);
  // And resume continues it.
  RunStopped(Cli() + " study resume --db " + db + " --participant P01 --quiet --stop-after 2");
  EXPECT_EQ(test::QueryInt(db, rated), committed + 4);
}

}  // namespace
}  // namespace hapticlab::session_cli_test
