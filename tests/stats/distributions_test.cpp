// The studentized range distribution against 25-digit quadrature (mpmath):
// tests/data/stats/tukey_reference.csv, made by tests/data/stats/tukey_reference.py, covers
// k = 2..20, df = 2..1000 and infinity, upper tails from 0.5 down to 1e-15, and issue #24's
// k = 10, df = 7, q = 27.7407. Required: 1e-8 relative on the upper tail P(Q > q) (the
// p-value) and on the lower tail P(Q <= q), both through TukeyFamily (what Tukey HSD uses)
// and through the direct PtukeyUpper/PtukeyLower (on every third row, for time).

#include "hapticlab/stats/distributions.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <utility>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::distributions_test {
namespace {

struct Row {
  int k;
  double df, q, upper, lower;
};

std::vector<Row> Rows() {
  const CsvTable t = ReadCsv(test::DataPath("stats/tukey_reference.csv"));
  const auto ck = t.Require("k"), cd = t.Require("df"), cq = t.Require("q"),
             cu = t.Require("upper"), cl = t.Require("lower");
  std::vector<Row> rows;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string& df = t.rows[r][cd];
    rows.push_back({std::stoi(t.rows[r][ck]), df == "Inf" ? INFINITY : std::stod(df),
                    std::stod(t.rows[r][cq]), std::stod(t.rows[r][cu]), std::stod(t.rows[r][cl])});
  }
  return rows;
}

TEST(TukeyAccuracy, UpperAndLowerTailsAgreeWithHighPrecisionQuadratureTo1e8Relative) {
  const auto rows = Rows();
  ASSERT_GE(rows.size(), 100u);
  std::map<std::pair<int, double>, std::unique_ptr<TukeyFamily>> families;
  double worst = 0;
  int tails_below_1e12 = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    auto& fam = families[{r.k, r.df}];
    if (!fam) fam = std::make_unique<TukeyFamily>(r.k, r.df);
    const std::string at =
        "k=" + std::to_string(r.k) + " df=" + std::to_string(r.df) + " q=" + std::to_string(r.q);
    const double up = fam->Upper(r.q), lo = fam->Lower(r.q);
    EXPECT_NEAR(up, r.upper, 1e-8 * r.upper) << at << " (TukeyFamily upper)";
    EXPECT_NEAR(lo, r.lower, 1e-8 * r.lower) << at << " (TukeyFamily lower)";
    worst = std::max({worst, std::abs(up / r.upper - 1), std::abs(lo / r.lower - 1)});
    if (r.upper < 1e-12) ++tails_below_1e12;
    if (i % 3 == 0 || (r.k == 10 && r.df == 7)) {
      const double dup = PtukeyUpper(r.q, r.k, r.df), dlo = PtukeyLower(r.q, r.k, r.df);
      EXPECT_NEAR(dup, r.upper, 1e-8 * r.upper) << at << " (PtukeyUpper)";
      EXPECT_NEAR(dlo, r.lower, 1e-8 * r.lower) << at << " (PtukeyLower)";
      worst = std::max({worst, std::abs(dup / r.upper - 1), std::abs(dlo / r.lower - 1)});
    }
  }
  EXPECT_GE(tails_below_1e12, 20);  // the vectors do reach the far tails
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", worst);
  RecordProperty("worst_relative_error", buf);
  std::printf("worst relative error over all rows and both tails: %s\n", buf);
}

// The reference file itself, where a closed form exists: for k = 2 the range of two normals
// is |difference|, so P(Q > q) = P(|T_df| > q / sqrt 2) (Boost's Student t, ~1e-15).
TEST(TukeyAccuracy, ReferenceRowsForTwoMeansMatchTheStudentTClosedForm) {
  int n = 0;
  for (const auto& r : Rows()) {
    if (r.k != 2) continue;
    ++n;
    const double exact = std::isinf(r.df) ? PnormTwoSided(r.q / std::sqrt(2.0))
                                          : PtTwoSided(r.q / std::sqrt(2.0), r.df);
    EXPECT_NEAR(r.upper, exact, 1e-12 * exact) << "df=" << r.df << " q=" << r.q;
  }
  EXPECT_GE(n, 20);
}

TEST(TukeyAccuracy, IssueCaseKTenDfSevenIsInTheVectors) {
  bool found = false;
  for (const auto& r : Rows()) found = found || (r.k == 10 && r.df == 7 && r.q == 27.7407);
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace hapticlab::stats::distributions_test
