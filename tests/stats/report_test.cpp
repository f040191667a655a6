// `hapticlab analyze`'s report: the dissertation's Table 5.4 layout, assumption flags and a
// sentence for every requested analysis that cannot run. The databases are written directly
// (planned trials of the shipped protocols, scores chosen here), so the expected tables are
// known exactly and the test costs milliseconds.

#include "hapticlab/stats/report.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::report_test {
namespace {

// Score of participant p (0-based) for a planned trial and criterion; nullopt: not rated.
using ScoreFn =
    std::function<std::optional<double>(int, const protocols::PlannedTrial&, const std::string&)>;

// Writes `participants` participants (codes P01, P02, ...) of the protocol into the database,
// every planned rated trial completed with the scores of `score`.
void WriteStudy(const std::string& db_path, const std::string& protocol_text, int participants,
                const ScoreFn& score) {
  const auto proto = protocols::ParseProtocol(protocol_text, "protocol");
  db::Database d(db_path);
  d.Exec("PRAGMA synchronous = OFF");  // a throw-away database: no fsync per trial
  const auto study = d.CreateStudy({.name = proto.name,
                                    .protocol_toml = protocol_text,
                                    .protocol_hash = "test",
                                    .seed = proto.seed});
  for (int p = 0; p < participants; ++p) {
    const std::string code = p < 9 ? "P0" + std::to_string(p + 1) : "P" + std::to_string(p + 1);
    const auto pid = d.AddParticipant({.study_id = study, .code = code, .index = p, .seed = 1});
    const auto sid =
        d.StartSession({.participant_id = pid, .software_version = "test", .device = "none"});
    for (const auto& t : protocols::Plan(proto, p)) {
      if (!t.rated) continue;
      const auto tid = d.AddTrial({.session_id = sid,
                                   .plan_index = t.index,
                                   .phase = t.phase,
                                   .material = t.material,
                                   .comparison = t.comparison,
                                   .method = t.method,
                                   .repetition = t.repetition,
                                   .left = t.left,
                                   .right = t.right});
      std::vector<db::Rating> ratings;
      for (const auto& c : proto.criteria)
        if (const auto s = score(p, t, c)) ratings.push_back({c, *s, 1.0});
      if (ratings.empty()) continue;
      d.StartTrial(tid);
      d.CompleteTrial(tid, ratings);
    }
    d.EndSession(sid, db::SessionStatus::kCompleted);
  }
}

std::string Section(const std::string& md, const std::string& from, const std::string& to) {
  const auto a = md.find(from);
  if (a == std::string::npos) return "";
  const auto b = md.find(to, a + from.size());
  return md.substr(a, b == std::string::npos ? std::string::npos : b - a);
}

TEST(Report, AggregateTablesHaveTheLayoutOfTable54) {
  // The chapter V.3 protocol, three participants whose per-cell means are exactly the
  // dissertation's Table 5.4 (roughness): participant offsets -1, 0, +1 cancel.
  const std::map<std::string, std::map<std::string, double>> table54 = {{"LPC",
                                                                         {{"Bamboo", 44.00},
                                                                          {"Denim", 58.67},
                                                                          {"RubberMat", 58.22},
                                                                          {"Tile", 61.33},
                                                                          {"Towel", 55.78},
                                                                          {"Wood", 56.67},
                                                                          {"Acryl", 66.44},
                                                                          {"Hardboard", 61.87},
                                                                          {"Cork", 65.11},
                                                                          {"Velvet", 67.00}}},
                                                                        {"FF",
                                                                         {{"Bamboo", 60.00},
                                                                          {"Denim", 69.22},
                                                                          {"RubberMat", 70.56},
                                                                          {"Tile", 54.64},
                                                                          {"Towel", 62.67},
                                                                          {"Wood", 69.67},
                                                                          {"Acryl", 72.89},
                                                                          {"Hardboard", 57.22},
                                                                          {"Cork", 57.16},
                                                                          {"Velvet", 50.02}}},
                                                                        {"Hybrid",
                                                                         {{"Bamboo", 62.11},
                                                                          {"Denim", 70.78},
                                                                          {"RubberMat", 73.22},
                                                                          {"Tile", 68.78},
                                                                          {"Towel", 65.22},
                                                                          {"Wood", 71.89},
                                                                          {"Acryl", 72.78},
                                                                          {"Hardboard", 58.24},
                                                                          {"Cork", 61.33},
                                                                          {"Velvet", 60.98}}}};
  test::TempDir dir;
  const std::string text =
      test::ReadFile(std::string(HL_SOURCE_DIR) + "/studies/shin2019/ch5-hybrid-realism.toml");
  WriteStudy(dir.File("ch5.db"), text, 3,
             [&](int p, const protocols::PlannedTrial& t, const std::string&) {
               return std::optional<double>(table54.at(t.method).at(t.material) +
                                            (p - 1) * (1 + t.repetition));
             });
  const auto r = Analyze(dir.File("ch5.db"), {.out_dir = dir.File("rep"), .figures = false});
  const std::string md = test::ReadFile(r.markdown);
  const std::string rough = Section(md, "### roughness", "### friction");
  ASSERT_FALSE(rough.empty()) << md;
  // As the dissertation prints it: an inhomogeneous table, then a homogeneous one; methods
  // as rows in protocol order (LPC, FF, Hybrid); materials in protocol order.
  const std::string expected =
      "**inhomogeneous**\n\n"
      "| method | Bamboo | Denim | RubberMat | Tile | Towel | Wood "
      "|\n|---|---|---|---|---|---|---|\n"
      "| LPC | 44.00 | 58.67 | 58.22 | 61.33 | 55.78 | 56.67 |\n"
      "| FF | 60.00 | 69.22 | 70.56 | 54.64 | 62.67 | 69.67 |\n"
      "| Hybrid | 62.11 | 70.78 | 73.22 | 68.78 | 65.22 | 71.89 |\n"
      "\n**homogeneous**\n\n"
      "| method | Acryl | Hardboard | Cork | Velvet |\n|---|---|---|---|---|\n"
      "| LPC | 66.44 | 61.87 | 65.11 | 67.00 |\n"
      "| FF | 72.89 | 57.22 | 57.16 | 50.02 |\n"
      "| Hybrid | 72.78 | 58.24 | 61.33 | 60.98 |\n";
  EXPECT_NE(rough.find(expected), std::string::npos) << rough;
  // Mauchly's test sits in the ANOVA table; with 3 participants the 10-level material
  // factor has no Mauchly test, and the report says so.
  EXPECT_NE(rough.find("| Mauchly W | p (Mauchly) |"), std::string::npos) << rough;
  EXPECT_NE(rough.find("Mauchly's test does not exist for material"), std::string::npos) << rough;
}

// A two-method study with a reference phase (tests/data/protocols/small.toml) asking for
// every analysis, and a one-method study without limits.
TEST(Report, UnrunnableAnalysesSayWhyAndViolationsAreFlagged) {
  test::TempDir dir;
  std::string small = test::ReadFile(test::DataPath("protocols/small.toml"));
  small +=
      "\n[analysis]\ntests = [\"rm-anova\", \"tukey\", \"kruskal\", \"grouping\", \"aggregate\", "
      "\"correlation\", \"shapiro\"]\n";
  const auto proto = protocols::ParseProtocol(small, "small");
  std::map<std::string, int> material_index;
  for (std::size_t i = 0; i < proto.materials.size(); ++i)
    material_index[proto.materials[i].id] = static_cast<int>(i);
  // FF's 32 participant x material cell means follow exponential quantiles (skewed: the
  // Shapiro-Wilk test rejects normality); Hybrid's are a symmetric triangle of values.
  // P08 never rated Cork with FF: dropped from the ANOVA and named.
  WriteStudy(
      dir.File("s.db"), small, 8,
      [&](int p, const protocols::PlannedTrial& t, const std::string& c) -> std::optional<double> {
        if (t.phase != protocols::PhaseKind::kMain)
          return t.material == t.comparison ? 80.0 - p : 30.0 + p;
        if (p == 7 && t.material == "Cork" && t.method == "FF") return std::nullopt;
        const int k = p * 4 + material_index.at(t.material);  // 0..31
        const double crit = c == "overall" ? 1.0 : 0.0;
        if (t.method == "FF")
          return 20.0 + 15.0 * -std::log(1.0 - (((k * 7) % 32) + 0.5) / 32.0) + crit;
        // Normal quantiles (Tukey's lambda approximation, lambda = 0.14) in a scrambled order.
        const double q = (((k * 5) % 32) + 0.5) / 32.0;
        return 50.0 + 10.0 * 4.91 * (std::pow(q, 0.14) - std::pow(1.0 - q, 0.14)) + crit;
      });
  const std::string one =
      "[study]\nname = \"one-method\"\nseed = 7\ncriteria = [\"roughness\"]\n"
      "[[material]]\nid = \"Denim\"\n[[material]]\nid = \"Cork\"\n[[material]]\nid = \"Acryl\"\n"
      "[[method]]\nname = \"FF\"\nalgorithm = \"fric2\"\n"
      "[[phase]]\nkind = \"main\"\nrepetitions = 2\n"
      "[analysis]\ntests = [\"rm-anova\", \"tukey\", \"grouping\", \"kruskal\", \"correlation\"]\n";
  // Denim's scores swing from participant to participant while Cork and Acryl move
  // together: the variances of the material differences are far from equal (sphericity
  // violated).
  WriteStudy(dir.File("s.db"), one, 8,
             [](int p, const protocols::PlannedTrial& t, const std::string&) {
               const int m = t.material == "Denim" ? 0 : t.material == "Cork" ? 1 : 2;
               return std::optional<double>(55.0 + p + (m == 0 ? 10.0 * ((p * 37) % 7 - 3) : 0.0) +
                                            (p * 3 + m) % 5);
             });
  const auto r = Analyze(dir.File("s.db"), {.out_dir = dir.File("rep"), .figures = false});
  const std::string md = test::ReadFile(r.markdown);
  const std::string two = Section(md, "## Study `test-small`", "## Study `one-method`");
  const std::string single = Section(md, "## Study `one-method`", "\n## ");
  ASSERT_FALSE(two.empty()) << md;
  ASSERT_FALSE(single.empty()) << md;
  // grouping on a two-method study: a sentence, no letters.
  EXPECT_NE(
      two.find(
          "*`grouping` was requested but not run: it compares the materials of a single method"),
      std::string::npos)
      << two;
  EXPECT_EQ(two.find("Dunn-Bonferroni"), std::string::npos) << two;
  // Normality is tested once, on the ANOVA's residuals; no bold alarm per method.
  EXPECT_NE(two.find("Normality of the ANOVA's residuals"), std::string::npos) << two;
  EXPECT_EQ(two.find("Normality violated"), std::string::npos) << two;
  // The scale the means, differences and CIs are in is named; the correlation names its unit
  // and n: main-phase trials rated on every criterion, 8 participants x (4 materials x 2
  // methods x 2 repetitions), less P08's 2 unrated FF Cork trials.
  EXPECT_NE(two.find("Rating scale: 0 to 100 (the protocol's `scale`)"), std::string::npos) << two;
  EXPECT_NE(two.find("n = 126 trials rated on every criterion"), std::string::npos) << two;
  // The dropped participant is named with the cell it lacks.
  const std::string dropped = Section(two, "- dropped P08: ", "\n");
  EXPECT_NE(dropped.find("Cork"), std::string::npos) << two;
  // One method, no reference phase: Tukey and grouping each say why they did not run.
  EXPECT_NE(single.find("*`tukey` was requested but not run: it compares methods"),
            std::string::npos)
      << single;
  EXPECT_NE(single.find("*`grouping` was requested but not run: it needs the real-real limits"),
            std::string::npos)
      << single;
  EXPECT_NE(single.find("Kruskal-Wallis on cell means by material"), std::string::npos) << single;
  EXPECT_NE(single.find("**Sphericity violated** for material: Mauchly's W = "), std::string::npos)
      << single;
  EXPECT_NE(single.find("The Greenhouse-Geisser correction is used"), std::string::npos) << single;
  EXPECT_EQ(two.find("**Sphericity violated**"), std::string::npos) << two;
  EXPECT_NE(
      single.find("*`correlation` was requested but not run: it needs an `overall` criterion"),
      std::string::npos)
      << single;
}

// One rule for significance: 3 participants x 5 materials, so the material effect has 4 df
// and 2 error df and Mauchly's test cannot be computed. The uncorrected p is 0.0187 and the
// Greenhouse-Geisser p 0.120 (R: the textbook computation on this matrix; afex agrees on F
// and the uncorrected p). Star, table, CSV and sentence must all follow the corrected p by
// default, and all follow the uncorrected one with correction = "none".
TEST(Report, StarsTableAndTextFollowTheCorrectedPWhereMauchlyCannotBeComputed) {
  const double scores[3][5] = {{35, 57, 76, 64, 71}, {45, 31, 44, 61, 64}, {32, 39, 53, 49, 68}};
  const std::vector<std::string> ids{"Bamboo", "Denim", "Tile", "Cork", "Velvet"};
  std::string text =
      "[study]\nname = \"few\"\ntitle = \"Few participants\"\nseed = 3\n"
      "criteria = [\"roughness\"]\n";
  for (const auto& id : ids) text += "[[material]]\nid = \"" + id + "\"\n";
  text +=
      "[[method]]\nname = \"FF\"\nalgorithm = \"fric2\"\n[[phase]]\nkind = \"main\"\n"
      "repetitions = 1\n[analysis]\ntests = [\"rm-anova\", \"shapiro\"]\n";
  test::TempDir dir;
  WriteStudy(dir.File("few.db"), text, 3,
             [&](int p, const protocols::PlannedTrial& t, const std::string&) {
               const auto m = std::find(ids.begin(), ids.end(), t.material) - ids.begin();
               return std::optional<double>(scores[p][m]);
             });
  for (const std::string correction : {"", "none"}) {
    const auto out = dir.File("rep" + correction);
    const auto r =
        Analyze(dir.File("few.db"), {.out_dir = out, .figures = false, .correction = correction});
    const std::string md = test::ReadFile(r.markdown);
    const std::string csv = test::ReadFile(out + "/few_roughness_rmanova.csv");
    SCOPED_TRACE(correction.empty() ? "GG (the protocol's default)" : correction);
    // The CSV's p_used (last column of the material row) is the p of the rule.
    const auto row = csv.substr(csv.find("\nmaterial,") + 1);
    const double p_used = std::stod(row.substr(row.rfind(',', row.find('\n')) + 1));
    const bool gg = correction.empty();
    EXPECT_NEAR(p_used, gg ? 0.1198727 : 0.0186537, 1e-6) << csv;
    EXPECT_NE(row.find(gg ? ",GG," : ",none,"), std::string::npos) << csv;
    // The table: star and p column agree with p_used; df are the corrected ones under GG.
    const bool starred = md.find("| material* |") != std::string::npos;
    EXPECT_EQ(starred, p_used < 0.05) << md;
    EXPECT_NE(md.find(gg ? "| material | 1.22, 2.43 | 5.630 | 0.120 |"
                         : "| material* | 4, 8 | 5.630 | 0.019 |"),
              std::string::npos)
        << md;
    // The sentences name the same p and never call the effect significant otherwise.
    EXPECT_NE(md.find("Mauchly's test does not exist for material"), std::string::npos) << md;
    EXPECT_NE(md.find(gg ? "Greenhouse-Geisser corrected p above is the one used (epsilon = "
                           "0.304, p = 0.120)"
                         : "the uncorrected p above assumes a sphericity that cannot be tested"),
              std::string::npos)
        << md;
    EXPECT_NE(md.find("Significance rule: "), std::string::npos) << md;
    EXPECT_EQ(md.find("read the Greenhouse-Geisser"), std::string::npos) << md;
    // The residuals' check: advice only if a p is near 0.05 (0.120 is not, 0.019 is).
    EXPECT_NE(md.find("Normality of the ANOVA's residuals"), std::string::npos) << md;
  }
}

// The analyses are registered by keyword: a toy analysis registered here, in the test binary,
// is accepted in a protocol's [analysis] tests, runs once per criterion after the built-in
// ones the protocol names, and writes its own section and file. The same study's `lmm` with
// `shapiro` checks the mixed model's conditional residuals.
TEST(Report, ARegisteredAnalysisRunsAndWritesItsOwnSection) {
  if (!FindAnalysis("toy-count"))
    RegisterAnalysis(
        {"toy-count", "counts the ratings", Analysis::Scope::kCriterion, [](AnalysisContext& c) {
           c.md << "\n#### toy-count of " << c.criterion << "\n\n"
                << c.ratings.rows() << " ratings, " << c.materials.size() << " materials\n";
           c.writer.Open(c.file_prefix + "_toy.csv") << "n\n" << c.ratings.rows() << "\n";
         }});
  std::string text = "[study]\nname = \"toy\"\nseed = 3\ncriteria = [\"roughness\", \"overall\"]\n";
  for (const char* id : {"Bamboo", "Denim", "Tile", "Cork"})
    text += std::string("[[material]]\nid = \"") + id + "\"\n";
  text +=
      "[[method]]\nname = \"FF\"\nalgorithm = \"fric2\"\n[[phase]]\nkind = \"main\"\n"
      "repetitions = 2\n[analysis]\ntests = [\"toy-count\", \"lmm\", \"shapiro\"]\n"
      "lmm_formula = \"score ~ material + (1 | participant)\"\n";
  const auto proto = protocols::ParseProtocol(text, "toy.toml");
  EXPECT_NO_THROW(CheckAnalyses(proto));
  test::TempDir dir;
  WriteStudy(dir.File("toy.db"), text, 5,
             [](int p, const protocols::PlannedTrial& t, const std::string& c) {
               return std::optional<double>(40.0 + 3 * p + static_cast<double>(t.material.size()) +
                                            7 * t.repetition + (c == "overall" ? 5 : 0) +
                                            (p * 7 + t.repetition) % 3);
             });
  const auto r = Analyze(dir.File("toy.db"), {.out_dir = dir.File("rep"), .figures = false});
  const std::string md = test::ReadFile(r.markdown);
  for (const std::string crit : {"roughness", "overall"}) {
    const std::string section =
        Section(md, "### " + crit, crit == "roughness" ? "### overall" : "\n## ");
    // 5 participants x 4 materials x 2 repetitions.
    EXPECT_NE(section.find("#### toy-count of " + crit + "\n\n40 ratings, 4 materials"),
              std::string::npos)
        << section;
    EXPECT_EQ(test::ReadFile(dir.File("rep/toy_" + crit + "_toy.csv")), "n\n40\n");
    EXPECT_NE(section.find("Normality of the mixed model's conditional residuals"),
              std::string::npos)
        << section;
    EXPECT_NE(section.find("40 residuals): Shapiro-Wilk W = "), std::string::npos) << section;
  }
  // The report lists the toy's files with the others.
  EXPECT_NE(std::find(r.files.begin(), r.files.end(), dir.File("rep/toy_overall_toy.csv")),
            r.files.end());
}

// A keyword no analysis is registered under is refused naming the file, the line of `tests`
// and every keyword there is; the built-in keywords are all registered.
TEST(Report, UnknownAnalysisKeywordsAreRefusedWithTheRegisteredNames) {
  const auto proto = protocols::ParseProtocol(
      "[study]\nname = \"x\"\nseed = 1\ncriteria = [\"c\"]\n[[material]]\nid = \"A\"\n"
      "[[method]]\nname = \"M\"\nalgorithm = \"fric2\"\n[[phase]]\nkind = \"main\"\n"
      "[analysis]\n\ntests = [\"rm-anova\", \"anova-rm\"]\n",
      "x.toml");
  try {
    CheckAnalyses(proto);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("x.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("x.toml:14"), std::string::npos) << what;
    EXPECT_NE(what.find("'anova-rm'"), std::string::npos) << what;
    EXPECT_NE(what.find("rm-anova, tukey"), std::string::npos) << what;
  }
  for (const char* name :
       {"rm-anova", "tukey", "kruskal", "grouping", "aggregate", "correlation", "shapiro", "lmm"})
    EXPECT_NE(FindAnalysis(name), nullptr) << name;
}

}  // namespace
}  // namespace hapticlab::stats::report_test
