// The report's tables and number formats (stats/src/report_tables.cpp): p-value formats and
// stars at their boundaries, the error bars' mean and 95 % CI over participant means (against
// Student's t quantile from R), levels in the protocol's order, the aggregate tables in the
// layout of Tables 5.4/5.5, and the ANOVA table reading the Greenhouse-Geisser p where
// Mauchly's test rejects sphericity.

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "../../stats/src/report_internal.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::stats::report_internal::report_tables_test {
namespace {

TEST(ReportTables, PValuesAndStarsAtTheirBoundaries) {
  EXPECT_EQ(P(0.0009), "< 0.001");
  EXPECT_EQ(P(0.001), "0.001");
  EXPECT_EQ(P(0.02), "0.020");
  EXPECT_EQ(PEq(0.0001), "p < 0.001");
  EXPECT_EQ(PEq(0.5), "p = 0.500");
  EXPECT_EQ(Stars(0.0099), "**");
  EXPECT_EQ(Stars(0.01), "*");
  EXPECT_EQ(Stars(0.0499), "*");
  EXPECT_EQ(Stars(0.05), "");
  EXPECT_EQ(Safe("Denim 2/x-y"), "Denim_2_x-y");
}

TEST(ReportTables, MeanAndCiAreOverParticipantMeans) {
  // Participants' means 1, 2, 3, 4 (each from two ratings, whose own spread must not count).
  LongTable t;
  t.key_names = {"participant", "method"};
  t.keys = {{"a", "a", "b", "b", "c", "c", "d", "d"}, {"x", "y", "x", "y", "x", "y", "x", "y"}};
  t.y = {0, 2, 1, 3, 2, 4, 3, 5};
  const auto [mean, half] = MeanCi(t);
  EXPECT_DOUBLE_EQ(mean, 2.5);
  // qt(0.975, 3) * sd(c(1, 2, 3, 4)) / sqrt(4) in R: 3.182446305284263 * 1.290994448735806 / 2.
  EXPECT_NEAR(half, 3.182446305284263 * 1.290994448735806 / 2, 1e-9);
  LongTable one = t.Where({{"participant", "a"}});
  EXPECT_TRUE(std::isnan(MeanCi(one).second));  // one participant: no interval
  EXPECT_TRUE(std::isnan(MeanCi(LongTable{.key_names = {"participant"}, .keys = {{}}}).first));
}

TEST(ReportTables, LevelsInTheProtocolsOrderThenTheRest) {
  EXPECT_EQ(InProtocolOrder({"FF", "Hybrid", "Vib"}, {"Zeta", "Vib", "FF", "Alpha"}),
            (std::vector<std::string>{"FF", "Vib", "Zeta", "Alpha"}));
  std::ostringstream md;
  NotRun(md, "friedman", "one method only");
  EXPECT_NE(md.str().find("`friedman` was requested but not run: one method only"),
            std::string::npos);
}

TEST(ReportTables, AggregateTablesOnePerMaterialGroup) {
  protocols::Protocol proto;
  proto.materials = {{.id = "Cork", .group = "homogeneous"},
                     {.id = "Denim", .group = "inhomogeneous"},
                     {.id = "Acryl", .group = "homogeneous"}};
  LongTable cm;
  cm.key_names = {"participant", "material", "method"};
  cm.keys = {{"a", "b", "a", "a"}, {"Cork", "Cork", "Denim", "Acryl"}, {"FF", "FF", "FF", "FF"}};
  cm.y = {40, 60, 30, 80};
  std::ostringstream md, agg;
  AggregateTables(md, agg, proto, "roughness", cm, {"FF", "Hybrid"}, {"Cork", "Denim", "Acryl"},
                  100);
  const std::string m = md.str();
  // Groups in the order the protocol first names them; within each, the materials' order.
  const auto homo = m.find("**homogeneous**"), inhomo = m.find("**inhomogeneous**");
  ASSERT_NE(homo, std::string::npos) << m;
  ASSERT_NE(inhomo, std::string::npos) << m;
  EXPECT_LT(homo, inhomo);
  EXPECT_NE(m.find("| method | Cork | Acryl |"), std::string::npos) << m;
  EXPECT_NE(m.find("| FF | 50.00 (0.50) | 80.00 (0.80) |"), std::string::npos) << m;
  EXPECT_NE(m.find("| Hybrid | | |"), std::string::npos) << m;  // no data: empty cells
  // CSV: criterion, group, material, method, mean, sd, n, ratio to the upper limit.
  EXPECT_NE(agg.str().find("roughness,homogeneous,Cork,FF,50.000000,14.142136,2,0.500000\n"),
            std::string::npos)
      << agg.str();
}

TEST(ReportTables, AnovaTableUsesTheCorrectedPWhereSphericityIsViolated) {
  RmAnovaResult a;
  a.subjects = {"a", "b", "c", "d", "e"};
  a.dropped_subjects = {"f"};
  a.dropped_reasons = {"no rating for method=FF"};
  // method: uncorrected p 0.03 but Mauchly rejects, corrected p 0.08: not significant.
  a.effects.push_back({.effect = "method",
                       .df1 = 2,
                       .df2 = 8,
                       .F = 5,
                       .p = 0.03,
                       .pes = 0.5,
                       .mauchly_defined = true,
                       .mauchly_W = 0.1,
                       .mauchly_p = 0.01,
                       .gg_epsilon = 0.6,
                       .p_gg = 0.08});
  // material: two levels, significant; no Mauchly test.
  a.effects.push_back({.effect = "material",
                       .df1 = 1,
                       .df2 = 4,
                       .F = 20,
                       .p = 0.01,
                       .pes = 0.8,
                       .gg_epsilon = 1,
                       .p_gg = 0.01});
  std::ostringstream md, csv;
  AnovaTable(md, csv, a);
  const std::string m = md.str();
  EXPECT_NE(m.find("(5 participants, 1 dropped for missing cells)"), std::string::npos) << m;
  EXPECT_NE(m.find("- dropped f: no rating for method=FF"), std::string::npos) << m;
  // GG (the default): the df and p columns are the corrected ones, and no star.
  EXPECT_NE(m.find("| method | 1.20, 4.80 | 5.000 | 0.080 | 0.500 | 0.100 | 0.010 (violated) | "
                   "0.600 | 0.000 |"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("| material* | 1, 4 | 20.000 | 0.010 | 0.800 | - | - | 1.000 |"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("**Sphericity violated** for method"), std::string::npos) << m;
  EXPECT_NE(m.find("corrected p = 0.080"), std::string::npos) << m;
  EXPECT_EQ(m.find("Sphericity violated** for material"), std::string::npos) << m;
  EXPECT_NE(m.find("Significance rule: "), std::string::npos) << m;
  EXPECT_NE(csv.str().find("method,2,8,5,0.03,0.5,0.1,0.01,0.6,0.08,0,0,GG,0.08\n"),
            std::string::npos)
      << csv.str();
  // correction = "none": the uncorrected p decides, and the text says what it assumes.
  std::ostringstream md0, csv0;
  AnovaTable(md0, csv0, a, Correction::kNone);
  const std::string m0 = md0.str();
  EXPECT_NE(m0.find("| method* | 2, 8 | 5.000 | 0.030 |"), std::string::npos) << m0;
  EXPECT_NE(m0.find("The uncorrected p above assumes sphericity"), std::string::npos) << m0;
  EXPECT_NE(csv0.str().find(",none,0.03\n"), std::string::npos) << csv0.str();
}

TEST(ReportTables, BetweenEffectsHaveNoSphericityCells) {
  RmAnovaResult a;
  a.subjects = {"a", "b", "c"};
  a.effects.push_back({.effect = "group",
                       .between_only = true,
                       .df1 = 1,
                       .df2 = 4,
                       .F = 9,
                       .p = 0.04,
                       .pes = 0.7,
                       .gg_epsilon = 1,
                       .p_gg = 0.04});
  std::ostringstream md, csv;
  AnovaTable(md, csv, a);
  EXPECT_NE(md.str().find("| group* | 1, 4 | 9.000 | 0.040 | 0.700 | - | - | - | - |"),
            std::string::npos)
      << md.str();
  EXPECT_NE(csv.str().find("group,1,4,9,0.04,0.7,,,,,,,GG,0.04\n"), std::string::npos) << csv.str();
}

}  // namespace
}  // namespace hapticlab::stats::report_internal::report_tables_test
