// hapticlab demo through the command line (apps/hapticlab/cmd_demo.cpp).

#include <gtest/gtest.h>

#include <filesystem>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_demo_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

TEST(StudyCli, DemoRunsEndToEnd) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " demo --participants 2 --out " + dir.File("d"), &out), 0)
      << out;
  EXPECT_NE(out.find("report:"), std::string::npos) << out;
  EXPECT_NE(out.find("real-time engine check"), std::string::npos) << out;
  std::string report;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.File("d")))
    if (e.path().filename() == "report.md") report = e.path().string();
  ASSERT_FALSE(report.empty());
  // The database: both simulated participants, every session and trial completed, and the
  // export holding every rating it stores.
  const auto run = std::filesystem::path(report).parent_path().parent_path();
  {
    db::Database d((run / "study.db").string(), {.create = false, .read_only = true});
    ASSERT_EQ(d.Studies().size(), 1u);
    const auto ps = d.Participants(d.Studies()[0].id);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps[0].code, "SIM01");
    EXPECT_EQ(ps[1].code, "SIM02");
    std::size_t rated = 0;
    for (const auto& p : ps)
      for (const auto& se : d.Sessions(p.id)) {
        EXPECT_EQ(se.status, db::SessionStatus::kCompleted) << p.code;
        for (const auto& t : d.Trials(se.id)) {
          EXPECT_EQ(t.status, db::TrialStatus::kCompleted) << p.code << " trial " << t.id;
          rated += d.Ratings(t.id).size();
        }
      }
    EXPECT_GT(rated, 0u);
    EXPECT_EQ(ReadCsv((run / "export/ratings.csv").string()).rows.size(), rated);
  }
  EXPECT_NE(out.find("power: participants for 80 % power on the method effect"), std::string::npos)
      << out;
  // ... rated by the protocol's calibrated observer, named with its hash.
  EXPECT_NE(out.find("observer the protocol's observer.toml (sha256 "), std::string::npos) << out;
  // The methods section carries timing figures: the sessions ran on a virtual clock, so the
  // report says so and adds the real-clock check's percentiles (measured, not asserted).
  const std::string md = test::ReadFile(report);
  EXPECT_NE(md.find("virtual clock"), std::string::npos) << md;
  const auto at = md.find("## Real-time check");
  ASSERT_NE(at, std::string::npos) << md;
  for (const char* s : {"requested 1000 Hz) achieved", "wake-up lateness p50", "p99.9",
                        "deadline misses", "requested 10000 Hz) achieved", "timer slack 1 ns"})
    EXPECT_NE(md.find(s, at), std::string::npos) << s << "\n" << md.substr(at);
}

TEST(DemoCli, ABadProtocolOrParticipantCountIsRefusedBeforeAnythingIsWritten) {
  test::TempDir dir;
  std::string out;
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " demo --protocol " + dir.File("none.toml") + " --out " + dir.File("d"), &out),
      2);
  EXPECT_NE(out.find(dir.File("none.toml")), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("d"))) << "a refused run left a folder behind";
  EXPECT_EQ(test::RunCommand(Cli() + " demo --participants 1 --out " + dir.File("d"), &out), 2);
  EXPECT_FALSE(std::filesystem::exists(dir.File("d")));
}

}  // namespace
}  // namespace hapticlab::cmd_demo_test
