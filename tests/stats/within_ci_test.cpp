// Within-subject confidence intervals (Cousineau 2005, Morey 2008) against the formula
// computed here from the raw ratings by a different route: the spread of each cell's
// deviations from the subject means (the grand mean is a constant and drops out), Boost's t
// quantile, Morey's sqrt(J / (J - 1)).

#include "hapticlab/stats/within_ci.hpp"

#include <gtest/gtest.h>

#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/descriptive.hpp"

namespace hapticlab::stats::within_ci_test {
namespace {

// participant x method x material with 2 repetitions; participant offsets are large.
LongTable Study(int participants, double offset_sd, std::uint64_t seed) {
  LongTable t;
  t.key_names = {"participant", "method", "material", "repetition"};
  t.keys.assign(4, {});
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const std::vector<std::string> methods{"FF", "Hybrid", "LPC"}, materials{"Cork", "Denim"};
  for (int p = 0; p < participants; ++p) {
    const double offset = offset_sd * g(rng);
    for (std::size_t m = 0; m < methods.size(); ++m)
      for (std::size_t a = 0; a < materials.size(); ++a)
        for (int r = 0; r < 2; ++r) {
          t.keys[0].push_back("P" + std::to_string(p));
          t.keys[1].push_back(methods[m]);
          t.keys[2].push_back(materials[a]);
          t.keys[3].push_back(std::to_string(r));
          t.y.push_back(50 + offset + 4.0 * static_cast<double>(m) - 3.0 * static_cast<double>(a) +
                        5 * g(rng));
        }
  }
  return t;
}

// Half-widths by the formula, from the rows: cell key -> (mean, half-width).
std::map<std::vector<std::string>, std::pair<double, double>> Formula(
    const LongTable& t, const std::vector<std::size_t>& factor_cols) {
  std::map<std::string, std::map<std::vector<std::string>, std::pair<double, int>>> sums;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    std::vector<std::string> cell;
    for (auto c : factor_cols) cell.push_back(t.keys[c][r]);
    auto& s = sums[t.keys[0][r]][cell];
    s.first += t.y[r];
    s.second += 1;
  }
  const double n = static_cast<double>(sums.size());
  const double J = static_cast<double>(sums.begin()->second.size());
  std::map<std::vector<std::string>, std::vector<double>> dev, raw;
  for (const auto& [subject, cells] : sums) {
    double subject_mean = 0;
    for (const auto& [cell, s] : cells) subject_mean += s.first / s.second / J;
    for (const auto& [cell, s] : cells) {
      dev[cell].push_back(s.first / s.second - subject_mean);
      raw[cell].push_back(s.first / s.second);
    }
  }
  const double t975 = boost::math::quantile(boost::math::students_t(n - 1), 0.975);
  std::map<std::vector<std::string>, std::pair<double, double>> out;
  for (const auto& [cell, d] : dev) {
    double m = 0, ss = 0;
    for (double x : d) m += x / n;
    for (double x : d) ss += (x - m) * (x - m);
    double mean = 0;
    for (double x : raw[cell]) mean += x / n;
    out[cell] = {mean, t975 * std::sqrt(ss / (n - 1) / n) * std::sqrt(J / (J - 1))};
  }
  return out;
}

TEST(WithinCi, HalfWidthsEqualCousineauMoreyOverMethodByMaterialCells) {
  const auto t = Study(9, 20, 1);
  const auto ci = WithinSubjectCi(t, "participant", {"method", "material"});
  const auto want = Formula(t, {1, 2});
  ASSERT_EQ(ci.size(), 6u);
  for (const auto& c : ci) {
    ASSERT_TRUE(want.count(c.cell));
    EXPECT_EQ(c.n, 9);
    EXPECT_NEAR(c.mean, want.at(c.cell).first, 1e-9);
    EXPECT_NEAR(c.half_width, want.at(c.cell).second, 1e-9) << c.cell[0] << " " << c.cell[1];
  }
  // One factor: materials and repetitions are averaged within each participant first (J = 3).
  const auto by_method = WithinSubjectCi(t, "participant", {"method"});
  const auto want_method = Formula(t, {1});
  ASSERT_EQ(by_method.size(), 3u);
  for (const auto& c : by_method)
    EXPECT_NEAR(c.half_width, want_method.at(c.cell).second, 1e-9) << c.cell[0];
}

TEST(WithinCi, ParticipantOffsetsLeaveThemUnchangedWhereBetweenSubjectCisGrow) {
  // The same within-participant pattern with small and with large participant offsets: the
  // within-subject CIs are identical (the offsets are what they remove), the CI of
  // participant means (the old error bars) grows with the offsets.
  const auto small = Study(8, 0, 3);
  LongTable shifted = small;
  for (std::size_t r = 0; r < shifted.rows(); ++r)
    shifted.y[r] += 30.0 * static_cast<double>(std::stoi(shifted.keys[0][r].substr(1)) % 4);
  const auto a = WithinSubjectCi(small, "participant", {"method"});
  const auto b = WithinSubjectCi(shifted, "participant", {"method"});
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i].half_width, b[i].half_width, 1e-9);
  const auto between = [](const LongTable& t) {
    return Describe(t.Where({{"method", "FF"}}).Average({"participant"}).y);
  };
  EXPECT_GT(between(shifted).ci95_hi - between(shifted).mean,
            3 * (between(small).ci95_hi - between(small).mean));
}

TEST(WithinCi, IncompleteParticipantsAreLeftOutAndTooFewGiveNaN) {
  const auto t = Study(4, 5, 7);
  // P0 lacks (LPC, Cork): left out, as afex_plot does.
  LongTable kept;
  kept.key_names = t.key_names;
  kept.keys.assign(4, {});
  for (std::size_t r = 0; r < t.rows(); ++r) {
    if (t.keys[0][r] == "P0" && t.keys[1][r] == "LPC" && t.keys[2][r] == "Cork") continue;
    for (std::size_t c = 0; c < 4; ++c) kept.keys[c].push_back(t.keys[c][r]);
    kept.y.push_back(t.y[r]);
  }
  const auto ci = WithinSubjectCi(kept, "participant", {"method", "material"});
  for (const auto& c : ci) EXPECT_EQ(c.n, 3);
  const auto one = WithinSubjectCi(t.Where({{"participant", "P1"}}), "participant", {"method"});
  for (const auto& c : one) EXPECT_TRUE(std::isnan(c.half_width));
  EXPECT_THROW(WithinSubjectCi(t, "participant", {}), InputError);
}

}  // namespace
}  // namespace hapticlab::stats::within_ci_test
