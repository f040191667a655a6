// Two simulated sites with a site effect injected in the observer (`study run --site
// --site-offset`), merged with `db merge` (byte-identical rerun, refusals), analysed: the LMM
// with (1 | site) recovers the injected site SD within its bootstrap interval and the pooled
// method effect of the same participants recorded without a site effect (docs/replication.md).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::replication_cli_test {
namespace {

using nlohmann::json;

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
Sites Analyse(const std::string& db, const std::string& out_dir, bool figures,
              const std::string& options = "") {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + out_dir +
                                 (figures ? "" : " --no-figures") + options,
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

// What docs/replication.md quotes from the worked example's report under "#### overall across
// sites": the site table's rows and the site SD sentence.
std::vector<std::string> DocumentedSiteLines() {
  const std::string doc = test::ReadFile(std::string(HL_SOURCE_DIR) + "/docs/replication.md");
  const auto at = doc.find("#### overall across sites");
  std::istringstream in(doc.substr(at == std::string::npos ? doc.size() : at));
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l) && l != "```";)
    if (l.rfind("| S0", 0) == 0 || l.rfind("| pooled", 0) == 0 || l.rfind("Site SD", 0) == 0)
      out.push_back(l);
  return out;
}

// The numbers of a line, in order.
std::vector<double> NumbersOf(const std::string& line) {
  static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]+)?)");
  std::vector<double> out;
  for (std::sregex_iterator it(line.begin(), line.end(), kNumber), end; it != end; ++it)
    out.push_back(std::stod(it->str()));
  return out;
}

// `report` (from its first line on) has a line with the label of the `documented` one (its first
// table cell, or its first two words) whose numbers are the documented ones, each within 1 % or
// 0.05, whichever is larger (another machine's libm may round a last bit otherwise, and a rating to
// the scale step with it).
void ExpectReportHasLine(const std::string& report, const std::string& documented) {
  const auto cut = documented.rfind("| ", 0) == 0 ? documented.find(" |", 2) : 7;
  const std::string label = documented.substr(0, cut);
  const auto at = report.find("\n" + label);
  ASSERT_NE(at, std::string::npos) << "no line '" << label << "' in the report:\n" << report;
  const std::string line = report.substr(at + 1, report.find('\n', at + 1) - at - 1);
  const auto want = NumbersOf(documented), got = NumbersOf(line);
  ASSERT_EQ(want.size(), got.size()) << documented << "\n" << line;
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_NEAR(got[i], want[i], std::max(0.05, 0.01 * std::abs(want[i])))
        << "number " << i + 1 << " of the documented line\n"
        << documented << "\nreport:\n"
        << line;
}

// Runs plan indices first..first+2 (codes P<index+1>) with `run_options` (the protocol, --plan,
// the rig), every rating shifted by `offset`.
void RunLab(const std::string& db, const std::string& run_options, double offset, int first) {
  for (int i = first; i < first + 3; ++i) {
    std::string out;
    ASSERT_EQ(
        test::RunCommand(Cli() + " study run " + run_options + " --db " + db + " --participant P0" +
                             std::to_string(i + 1) + " --index " + std::to_string(i) +
                             " --site-offset " + std::to_string(offset) + " --quiet --record none",
                         &out),
        0)
        << out;
  }
}

// Every session of a database: site code and provenance.
std::vector<std::pair<std::string, json>> SessionsOf(const std::string& path) {
  std::vector<std::pair<std::string, json>> out;
  const db::Database d = db::OpenForReading(path);
  for (const auto& st : d.Studies())
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id))
        out.emplace_back(se.site_code, json::parse(se.provenance_json));
  return out;
}

std::string Sha256sum(const std::string& file) {
  std::string out;
  EXPECT_EQ(test::RunCommand("sha256sum " + file, &out), 0) << out;
  return out.substr(0, 64);
}

// docs/replication.md's worked example, end to end. Lab A (site S01, the simulated rig) freezes
// the small protocol and bundles the plan; lab B imports the bundle as site S02 for a Falcon
// twin whose rig file turns both samples 30 degrees about their normals, and runs the plan's
// protocol with one key changed (one different pair in the reference phase, the plan's two).
// Each lab runs three simulated participants under the plan with a site offset (+6 / -6
// points); the databases merge, and `analyze --plan` of the merged file recovers the injected
// site SD and the pooled method effect of the same runs without a site effect, and lists lab
// B's changed key with its sessions.
TEST(ReplicationCli, WorkedExampleFreezeBundleImportRunAtTwoSitesMergeAnalyze) {
  test::TempDir dir;
  const std::string plan = dir.File("plan"), site = dir.File("siteB");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " study freeze " + Small() + " -o " + plan +
                                 " --no-power --rig-device sim && " + Cli() + " study bundle " +
                                 plan + " -o " + dir.File("study.hlbundle") + " && " + Cli() +
                                 " study import " + dir.File("study.hlbundle") +
                                 " --site S02 --device falcon-twin -o " + site,
                             &out),
            0)
      << out;
  const std::string hash = test::ReadFile(plan + "/PLAN.sha256").substr(0, 64);
  // Lab B's rig file: the Falcon's samples where the twin holds them, turned in their plane.
  const auto turned = [](const std::string& x) {
    return "origin_m = [" + x +
           ", -0.04, 0.125]\nx_axis = [0.8660254, 0, -0.5]\nz_axis = [0, 1, 0]\n";
  };
  test::WriteFile(site + "/rig.toml", "device = \"falcon-twin\"\n[sample.left]\n" +
                                          turned("-0.025") + "[sample.right]\n" + turned("0.025"));
  std::filesystem::create_directories(dir.File("changed"));
  std::filesystem::copy_file(site + "/plan/protocol/profiles.toml",
                             dir.File("changed/profiles.toml"));
  std::string proto = test::ReadFile(site + "/plan/protocol/small.toml");
  const std::string key = "different_pairs = 2";
  ASSERT_NE(proto.find(key), std::string::npos);
  proto.replace(proto.find(key), key.size(), "different_pairs = 1");
  test::WriteFile(dir.File("changed/small.toml"), proto);
  const std::string lab_a = "--plan " + plan + " --site S01";
  // No --site: the site directory's code.
  const std::string lab_b = dir.File("changed/small.toml") + " --plan " + site +
                            " --device falcon-twin --rig " + site + "/rig.toml";
  const auto a = dir.File("a.db"), b = dir.File("b.db"), all = dir.File("all.db");
  RunLab(a, lab_a, 6, 0);
  RunLab(b, lab_b, -6, 3);
  const std::string rig_a = SessionsOf(a).at(0).second["rig"].value("file_sha256", "");
  for (const auto& [code, prov] : SessionsOf(a)) {
    EXPECT_EQ(code, "S01");
    EXPECT_EQ(prov["plan_sha256"], hash);
    EXPECT_FALSE(prov.contains("plan_site") || prov.contains("plan_protocol_changes"));
  }
  for (const auto& [code, prov] : SessionsOf(b)) {
    EXPECT_EQ(code, "S02");
    EXPECT_EQ(prov["plan_site"], "S02");
    EXPECT_EQ(prov["plan_sha256"], hash);
    EXPECT_EQ(prov["device"], "falcon-twin");
    EXPECT_EQ(prov["rig"]["file_sha256"], Sha256sum(site + "/rig.toml"));
    EXPECT_NE(prov["rig"]["file_sha256"], rig_a);
    EXPECT_EQ(prov["plan_protocol_changes"], json::array({"phase[1].different_pairs: 2 -> 1"}));
  }
  // The study's protocol differs between the labs: refused unless allowed.
  EXPECT_EQ(test::RunCommand(Cli() + " db merge " + a + " " + b + " -o " + all, &out), 2) << out;
  EXPECT_NE(out.find(a), std::string::npos) << out;
  EXPECT_NE(out.find(b), std::string::npos) << out;
  const std::string merge = " --allow-different-protocols -o ";
  ASSERT_EQ(test::RunCommand(Cli() + " db merge " + a + " " + b + merge + all, &out), 0) << out;

  const Sites with = Analyse(all, dir.File("rep"), false, " --plan " + plan);
  const std::string md = test::ReadFile(dir.File("rep/report.md"));
  EXPECT_NE(md.find("Sessions recorded under this plan: 6 of 6"), std::string::npos) << md;
  // The merged study row holds lab A's protocol: lab B's change comes from its sessions.
  EXPECT_NE(md.find("| 1 | protocol key changed | phase[1].different_pairs: 2 -> 1 — 3 "
                    "session(s): S02:P04, S02:P05, S02:P06 |\n"),
            std::string::npos)
      << md;
  // The docs quote this walk's numbers: they are the report's.
  const auto quoted = DocumentedSiteLines();
  EXPECT_EQ(quoted.size(), 4u) << "docs/replication.md: the site table and its SD line";
  const auto overall = md.find("#### overall across sites");
  for (const auto& l : quoted)
    ExpectReportHasLine(md.substr(overall == std::string::npos ? md.size() : overall), l);
  const double injected = 12 / std::sqrt(2.0);  // offsets +6 and -6, as a variance component
  EXPECT_LE(with.low, injected);
  EXPECT_GE(with.high, injected);
  EXPECT_GT(with.sd, 0.5 * injected);
  // The same participants and rigs without a site effect: the same pooled method effect.
  const auto a0 = dir.File("a0.db"), b0 = dir.File("b0.db"), all0 = dir.File("all0.db");
  RunLab(a0, lab_a, 0, 0);
  RunLab(b0, lab_b, 0, 3);
  ASSERT_EQ(test::RunCommand(Cli() + " db merge " + a0 + " " + b0 + merge + all0, &out), 0) << out;
  const Sites without = Analyse(all0, dir.File("rep0"), false);
  EXPECT_NEAR(with.pooled, without.pooled, 0.5);
  EXPECT_LT(without.sd, with.sd);
  std::printf(
      "site SD %.2f [%.2f, %.2f] (injected %.2f), pooled %.2f (no site effect: %.2f, "
      "site SD %.2f)\n",
      with.sd, with.low, with.high, injected, with.pooled, without.pooled, without.sd);
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
}  // namespace hapticlab::replication_cli_test
