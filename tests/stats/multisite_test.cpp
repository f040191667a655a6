// The multi-site analysis (stats/multisite.hpp): the LMM with a site term against lme4 on
// ratings HapticLab recorded at two simulated sites and merged (lmm_sites_reference.R), the
// paired-t power and d33 against R's power.t.test, the forest plot read back by OpenCV.

#include "hapticlab/stats/multisite.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/plot.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::multisite_test {
namespace {

using nlohmann::json;

json SitesRef() {
  std::ifstream f(test::DataPath("stats/lmm_sites_reference.json"));
  return json::parse(f);
}

LongTable SitesData() {
  return ReadLongCsv(test::DataPath("stats/lmm_sites.csv"), "score",
                     {"site", "participant", "method", "material"});
}

void ExpectRel(double got, double want, double rel, const std::string& what, double floor = 1) {
  EXPECT_NEAR(got, want, rel * std::max(std::abs(want), floor)) << what;
}

TEST(MultiSite, LmmWithASiteTermEqualsLme4OnMergedRatings) {
  const json ref = SitesRef();
  const LongTable d = SitesData();
  const auto& r = ref["reml"];
  // Hybrid - FF as the report builds it (FitMultiSite's contrast) and as lmerTest's contest1D.
  const auto fit = FitMultiSite(d, {"FF", "Hybrid"}, {.bootstrap = 0});
  ASSERT_EQ(fit.formula, ref["formula"].get<std::string>());
  const LmmResult& m = fit.model;
  EXPECT_TRUE(m.converged) << m.message;
  constexpr double kRel = 1e-4;
  ExpectRel(m.sigma, r["sigma"], kRel, "sigma");
  ExpectRel(m.logLik, r["logLik"], 1e-6, "logLik");
  ASSERT_EQ(m.fixed.size(), r["fixed"].size());
  for (std::size_t i = 0; i < m.fixed.size(); ++i) {
    const auto& w = r["fixed"][i];
    SCOPED_TRACE(m.fixed[i].name);
    EXPECT_EQ(m.fixed[i].name, w["name"].get<std::string>());
    ExpectRel(m.fixed[i].estimate, w["estimate"], kRel, "estimate");
    ExpectRel(m.fixed[i].se, w["se"], kRel, "se", 0.01);
    ExpectRel(m.fixed[i].df, w["df"], 1e-3, "df");
  }
  // Variance components: every SD of lme4's VarCorr (correlations not compared here).
  for (const auto& w : r["random"]) {
    const std::string group = w["group"], var1 = w["var1"], var2 = w["var2"];
    if (!var2.empty()) continue;
    SCOPED_TRACE(group + " " + var1);
    if (group == "Residual") continue;
    bool found = false;
    for (const auto& t : m.random)
      if (t.group == group)
        for (std::size_t k = 0; k < t.names.size(); ++k)
          if (t.names[k] == var1) {
            found = true;
            EXPECT_NEAR(t.sd[k], w["sdcor"].get<double>(), 1e-3 * std::max(1.0, t.sd[k]));
          }
    EXPECT_TRUE(found);
  }
  const auto& c = r["contrast"];
  EXPECT_EQ(fit.pooled.name, c["name"].get<std::string>());
  ExpectRel(fit.pooled.estimate, c["estimate"], kRel, "contrast");
  ExpectRel(fit.pooled.se, c["se"], kRel, "contrast se", 0.01);
  ExpectRel(fit.pooled.df, c["df"], 1e-3, "contrast df");
  ExpectRel(fit.pooled.p, c["p"], 1e-3, "contrast p", 1e-6);
  // The site SD is the model's (1 | site) term.
  for (const auto& w : r["random"])
    if (w["group"] == "site") {
      EXPECT_NEAR(fit.site_sd, w["sdcor"].get<double>(), 1e-3);
    }
}

// Per-site effects are the participants' mean differences; the pooled raw means are the means
// of the participants' means.
TEST(MultiSite, PerSiteEffectsAreParticipantMeanDifferences) {
  const LongTable d = SitesData();
  const auto fit = FitMultiSite(d, {"FF", "Hybrid"}, {.bootstrap = 0});
  ASSERT_EQ(fit.sites.size(), 2u);
  for (const auto& s : fit.sites) {
    SCOPED_TRACE(s.site);
    const LongTable at = d.Where({{"site", s.site}});
    double sum = 0;
    const auto parts = at.Levels("participant");
    for (const auto& p : parts) {
      const auto mean = [&](const std::string& m) {
        const auto t = at.Where({{"participant", p}, {"method", m}});
        double x = 0;
        for (double y : t.y) x += y;
        return x / static_cast<double>(t.rows());
      };
      sum += mean("Hybrid") - mean("FF");
    }
    EXPECT_EQ(s.participants, static_cast<int>(parts.size()));
    EXPECT_NEAR(s.estimate, sum / static_cast<double>(parts.size()), 1e-9);
    EXPECT_LT(s.low, s.estimate);
    EXPECT_GT(s.high, s.estimate);
  }
}

// R 4.2.2: power.t.test(n = 15, delta = d, type = "paired", strict = TRUE)$power and
// power.t.test(n = 15, power = 1/3, type = "paired", strict = TRUE, tol = 1e-12)$delta.
TEST(MultiSite, PairedPowerAndD33AgreeWithR) {
  EXPECT_NEAR(PairedTPower(0.8, 15), 0.8213105387, 1e-6);
  EXPECT_NEAR(PairedTPower(0.3, 15), 0.1915313471, 1e-6);
  EXPECT_NEAR(PairedTPower(0.0, 15), 0.05, 1e-6);
  EXPECT_NEAR(SmallTelescopeD33(15), 0.4235762866, 1e-5);
}

TEST(MultiSite, ReplicationStatementFollowsTheSmallTelescopesRule) {
  MultiSiteFit f;
  f.first = "LPC";
  f.last = "Hybrid";
  f.sites.resize(3);
  f.participants = 30;
  f.sd_difference = 10;  // d33 = 0.4236 * 10 = 4.24 points
  f.pooled.df = 28;
  const OriginalEffect orig{7.0, 15, "Table 5.4"};
  auto with = [&](double est, double se) {
    f.pooled.estimate = est;
    f.pooled.se = se;
    f.pooled_low = est - 2.048 * se;
    f.pooled_high = est + 2.048 * se;
    return ReplicationStatement(f, orig);
  };
  EXPECT_NE(with(6.0, 1.0).find("Replicated"), std::string::npos);
  EXPECT_NE(with(6.0, 1.0).find("inside the pooled 95 % CI"), std::string::npos);
  EXPECT_NE(with(0.5, 1.0).find("Small-telescopes failure"), std::string::npos);
  EXPECT_NE(with(0.5, 1.0).find("outside"), std::string::npos);
  EXPECT_NE(with(2.0, 2.0).find("Inconclusive"), std::string::npos);
  // The original's direction decides: an effect opposite to a negative original.
  EXPECT_NE(with(3.0, 1.0).find("Replicated"), std::string::npos);
  const OriginalEffect negative{-7.0, 15, "x"};
  f.pooled.estimate = 3.0;
  EXPECT_EQ(ReplicationStatement(f, negative).find("Replicated"), std::string::npos);
  // Ch. V.3 originals: Hybrid - LPC from Tables 5.4/5.5; none for other protocols.
  const auto ro = ShinOriginalEffect("shin2019-ch5-hybrid-realism", "roughness", "LPC", "Hybrid");
  ASSERT_TRUE(ro);
  EXPECT_NEAR(ro->effect, 66.533 - 59.509, 1e-9);
  EXPECT_EQ(ro->participants, 15);
  EXPECT_FALSE(ShinOriginalEffect("test-small", "roughness", "LPC", "Hybrid"));
  EXPECT_FALSE(ShinOriginalEffect("shin2019-ch5-hybrid-realism", "friction", "LPC", "Hybrid"));
}

// The forest plot read back: markers on a linear x axis (site squares blue, the pooled
// diamond orange, one row below the other), both formats written.
TEST(MultiSite, ForestPlotMarkersSitWhereTheEstimatesAre) {
  test::TempDir dir;
  ForestPlot fp{.title = "t", .x_label = "effect"};
  fp.rows = {{"S1", -5, -8, -2, false}, {"S2", 10, 7, 13, false}, {"pooled", 2.5, 0, 5, true}};
  const auto files = DrawForestPlot(fp, dir.File("forest"));
  ASSERT_EQ(files.size(), 3u);  // SVG, PNG and PDF
  EXPECT_NE(test::ReadFile(files[0]).find("<svg"), std::string::npos);
  EXPECT_EQ(test::ReadFile(files[2]).rfind("%PDF-", 0), 0u);
  const cv::Mat img = cv::imread(files[1], cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const cv::Vec3b blue(178, 114, 0), orange(0, 159, 230);
  // Centroids of each colour's pixels in the upper and lower halves of the blue rows.
  struct Blob {
    double x = 0, y = 0;
    int n = 0;
  };
  std::vector<Blob> blues(2);
  Blob pooled;
  int mid_row = -1;
  {
    std::vector<int> rows;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x)
        if (img.at<cv::Vec3b>(y, x) == blue) rows.push_back(y);
    ASSERT_GT(rows.size(), 100u);
    mid_row = (rows.front() + rows.back()) / 2;
  }
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const auto& p = img.at<cv::Vec3b>(y, x);
      Blob* b = p == blue ? &blues[y < mid_row ? 0 : 1] : p == orange ? &pooled : nullptr;
      if (!b) continue;
      b->x += x;
      b->y += y;
      ++b->n;
    }
  for (auto* b : {&blues[0], &blues[1], &pooled}) {
    ASSERT_GT(b->n, 50);
    b->x /= b->n;
    b->y /= b->n;
  }
  // Rows top to bottom: S1, S2, pooled.
  EXPECT_LT(blues[0].y, blues[1].y);
  EXPECT_LT(blues[1].y, pooled.y);
  // x is linear in the estimate: (x(S2) - x(S1)) / (x(pooled) - x(S1)) = 15 / 7.5.
  EXPECT_NEAR((blues[1].x - blues[0].x) / (pooled.x - blues[0].x), 2.0, 0.03);
  EXPECT_THROW(DrawForestPlot({}, dir.File("empty")), std::exception);
}

}  // namespace
}  // namespace hapticlab::stats::multisite_test
