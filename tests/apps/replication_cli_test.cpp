// Two simulated sites with a site effect injected in the observer (`study run --site
// --site-offset`), merged with `db merge` (byte-identical rerun, refusals), analysed: the LMM
// with (1 | site) recovers the injected site SD within its bootstrap interval and the pooled
// method effect of the same participants recorded without a site effect (docs/replication.md).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
namespace {

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

std::string Bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

// Site `site` runs three participants with plan indices first..first+2 (codes P<index+1>),
// every rating shifted by `offset`.
void RunSite(const std::string& db, const std::string& site, double offset, int first) {
  for (int i = first; i < first + 3; ++i) {
    std::string out;
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + db +
                                   " --participant P0" + std::to_string(i + 1) + " --index " +
                                   std::to_string(i) + " --site " + site + " --site-offset " +
                                   std::to_string(offset) + " --quiet --record none",
                               &out),
              0)
        << out;
  }
}

// The pooled "overall" method effect and the site SD interval of a merged database's report.
struct Sites {
  double pooled = 0, sd = 0, low = 0, high = 0;
};
Sites Analyse(const std::string& db, const std::string& out_dir, bool figures) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + out_dir +
                                 (figures ? "" : " --no-figures"),
                             &out),
            0)
      << out;
  const std::string md = test::ReadFile(out_dir + "/report.md");
  EXPECT_NE(md.find("### Sites"), std::string::npos);
  const auto at = md.find("#### overall across sites");
  EXPECT_NE(at, std::string::npos) << md;
  std::smatch m;
  const std::string tail = md.substr(at == std::string::npos ? 0 : at);
  Sites s;
  if (std::regex_search(tail, m,
                        std::regex(R"(Site SD ([0-9.]+) points \(95 % parametric-bootstrap )"
                                   R"(percentile interval \[([0-9.]+), ([0-9.]+)\])")))
    s = {0, std::stod(m[1]), std::stod(m[2]), std::stod(m[3])};
  else
    ADD_FAILURE() << tail;
  const auto csv = ReadCsv(out_dir + "/test-small_overall_sites.csv");
  const auto site = csv.Require("site"), effect = csv.Require("effect");
  for (const auto& row : csv.rows)
    if (row[site] == "pooled") s.pooled = std::stod(row[effect]);
  EXPECT_EQ(std::filesystem::exists(out_dir + "/test-small_overall_sites.png"), figures);
  return s;
}

TEST(ReplicationCli, TwoSitesMergeAndTheSiteModelRecoversTheInjectedSiteSd) {
  test::TempDir dir;
  const auto a = dir.File("a.db"), b = dir.File("b.db"), all = dir.File("all.db");
  RunSite(a, "S1", 6, 0);
  RunSite(b, "S2", -6, 3);
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " db merge " + a + " " + b + " -o " + all, &out), 0) << out;
  EXPECT_NE(out.find("sites S1, S2, 6 participants"), std::string::npos) << out;
  // A rerun, inputs in the other order: the same bytes.
  ASSERT_EQ(
      test::RunCommand(Cli() + " db merge " + b + " " + a + " -o " + dir.File("again.db"), &out), 0)
      << out;
  EXPECT_TRUE(Bytes(all) == Bytes(dir.File("again.db")));
  // Refused, exit 2: the database with itself; a participant in both inputs.
  EXPECT_EQ(test::RunCommand(Cli() + " db merge " + a + " " + a + " -o " + dir.File("x.db"), &out),
            2);
  EXPECT_NE(out.find("itself"), std::string::npos) << out;
  EXPECT_EQ(
      test::RunCommand(Cli() + " db merge " + all + " " + a + " -o " + dir.File("x.db"), &out), 2);
  EXPECT_NE(out.find(all), std::string::npos) << out;
  EXPECT_NE(out.find(a), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("x.db")));
  // A site code shaped like a name is refused before anything is written.
  EXPECT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + dir.File("n.db") +
                                 " --participant P01 --site Berlin1 --quiet --record none",
                             &out),
            2);
  EXPECT_NE(out.find("is not a site code"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("n.db")));

  const Sites with = Analyse(all, dir.File("rep"), true);
  // The injected offsets +6 and -6: SD 8.49 points (n - 1 denominator, as a variance
  // component); the model's estimate and its interval.
  const double injected = 12 / std::sqrt(2.0);
  EXPECT_LE(with.low, injected);
  EXPECT_GE(with.high, injected);
  EXPECT_GT(with.sd, 0.5 * injected);
  // The same participants without a site effect: the pooled method effect is the same (an
  // additive offset moves both methods alike; ratings clamped at the scale's ends may differ).
  const auto a0 = dir.File("a0.db"), b0 = dir.File("b0.db"), all0 = dir.File("all0.db");
  RunSite(a0, "S1", 0, 0);
  RunSite(b0, "S2", 0, 3);
  ASSERT_EQ(test::RunCommand(Cli() + " db merge " + a0 + " " + b0 + " -o " + all0, &out), 0) << out;
  const Sites without = Analyse(all0, dir.File("rep0"), false);
  EXPECT_NEAR(with.pooled, without.pooled, 0.5);
  EXPECT_LT(without.sd, with.sd);
}

// study power --sites: K x n participants per simulated study, the site offsets named.
TEST(ReplicationCli, PowerForSitesTimesParticipants) {
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " study power " + Small() +
                                 " --observer builtin --sites 2 --participants-per-site 3"
                                 " --site-sd 5 --simulations 4 --pool 1 --effect method --quiet",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("2 sites x n participants per site"), std::string::npos) << out;
  EXPECT_NE(out.find("SD 5 rating points"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(
                Cli() + " study power " + Small() + " --observer builtin --sites 0 --quiet", &out),
            2)
      << out;
}

}  // namespace
}  // namespace hapticlab
