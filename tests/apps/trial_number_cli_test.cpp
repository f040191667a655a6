// One trial number everywhere: the run's log, `study plan`, events.csv and the CSV export give
// a trial the same number, its 1-based place in the participant's plan, also when faults
// re-queue trials (so the order of completion differs from the plan's) and never a database id.

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::trial_number_cli_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// Column `name` of a CSV table.
std::size_t Col(const CsvTable& t, const std::string& name) {
  for (std::size_t i = 0; i < t.header.size(); ++i)
    if (t.header[i] == name) return i;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

TEST(TrialNumberCli, LogPlanEventsAndExportsAgree) {
  test::TempDir dir;
  const std::string protocol = test::DataPath("protocols/small.toml");
  const std::string db = dir.File("s.db");
  std::string log;
  ASSERT_EQ(test::RunCommand(Cli() + " study run " + protocol + " --db " + db +
                                 " --participant P01 --record force --inject-faults 0.3",
                             &log),
            0)
      << log;
  ASSERT_EQ(test::RunCommand(Cli() + " export --db " + db + " --format csv --out " + dir.File("x")),
            0);
  std::string plan;
  ASSERT_EQ(
      test::RunCommand(Cli() + " study plan " + protocol + " --participant P01 --db " + db, &plan),
      0)
      << plan;
  // The plan as `study plan` prints it: number -> (phase, material); breaks before numbers.
  std::map<int, std::pair<std::string, std::string>> planned;
  std::set<int> break_before;
  {
    std::istringstream in(plan);
    bool brk = false;
    int total = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.find("--- break ---") != std::string::npos) brk = true;
      std::smatch m;
      if (std::regex_search(line, m, std::regex(R"(^\s*(\d+)\s+(\w+)\s+(\S+))"))) {
        const int n = std::stoi(m[1]);
        planned[n] = {m[2], m[3]};
        if (brk) break_before.insert(n);
        brk = false;
        total = std::max(total, n);
      }
    }
    ASSERT_EQ(static_cast<int>(planned.size()), total);
  }
  // The log: "P01 trial N/M (phase material method) done; K of M completed".
  std::vector<int> logged;
  bool out_of_order = false;
  {
    std::istringstream in(log);
    const std::regex re(R"(P01 trial (\d+)/(\d+) \((\w+) (\S+) .*\) done; (\d+) of)");
    for (std::string line; std::getline(in, line);) {
      std::smatch m;
      if (!std::regex_search(line, m, re)) continue;
      const int n = std::stoi(m[1]);
      EXPECT_EQ(std::stoi(m[2]), static_cast<int>(planned.size()));
      ASSERT_TRUE(planned.count(n)) << line;
      EXPECT_EQ(planned[n].first, m[3]) << line;
      EXPECT_EQ(planned[n].second, m[4]) << line;
      out_of_order = out_of_order || n != std::stoi(m[5]);
      logged.push_back(n);
    }
  }
  EXPECT_EQ(std::set<int>(logged.begin(), logged.end()).size(), planned.size());
  EXPECT_TRUE(out_of_order) << "no fault re-queued a trial; the test would not tell numbers apart";
  // trials.csv and ratings.csv: the same number for the same phase and material.
  const auto trials = ReadCsv(dir.File("x/trials.csv"));
  EXPECT_EQ(trials.rows.size(), planned.size());
  std::set<int> refaulted;
  for (const auto& r : trials.rows) {
    const int n = std::stoi(r[Col(trials, "trial")]);
    ASSERT_TRUE(planned.count(n));
    EXPECT_EQ(r[Col(trials, "phase")], planned[n].first);
    EXPECT_EQ(r[Col(trials, "material")], planned[n].second);
    if (std::stoi(r[Col(trials, "attempts")]) > 1) refaulted.insert(n);
  }
  const auto ratings = ReadCsv(dir.File("x/ratings.csv"));
  ASSERT_FALSE(ratings.rows.empty());
  for (const auto& r : ratings.rows) {
    const int n = std::stoi(r[Col(ratings, "trial")]);
    EXPECT_EQ(r[Col(ratings, "material")], planned[n].second) << "trial " << n;
  }
  // events.csv: the faults name the re-run trials, the planned breaks the plan's.
  const auto events = ReadCsv(dir.File("x/events.csv"));
  std::set<int> faulted, breaks;
  for (const auto& r : events.rows) {
    const std::string& cell = r[Col(events, "trial")];
    if (cell.empty()) continue;
    const int n = std::stoi(cell);
    EXPECT_TRUE(planned.count(n)) << "event trial " << n;
    if (r[Col(events, "kind")] == "device-fault") faulted.insert(n);
    if (r[Col(events, "kind")] == "break-planned") breaks.insert(n);
  }
  EXPECT_FALSE(faulted.empty());
  EXPECT_EQ(faulted, refaulted);
  EXPECT_EQ(breaks, break_before);
  EXPECT_FALSE(breaks.empty());
}

}  // namespace
}  // namespace hapticlab::trial_number_cli_test
