// Distribution functions and small tests against tests/data/stats/vectors.csv (R 4.2.2 and
// high-precision references; see tests/data/stats/README.md). Each row carries its own
// tolerance; where a row gives both an absolute and a relative tolerance, both must hold.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::reference_vectors_test {
namespace {

std::map<std::string, std::string> Args(const std::string& s) {
  std::map<std::string, std::string> m;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ';')) {
    const auto eq = part.find('=');
    m[part.substr(0, eq)] = part.substr(eq + 1);
  }
  return m;
}

double Num(const std::string& s) { return s == "Inf" ? INFINITY : std::stod(s); }

std::vector<double> Numbers(const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string x;
  while (ss >> x) v.push_back(std::stod(x));
  return v;
}

double Qnorm(double p) {
  // Inverse of PnormUpper by bisection (test-only; the library uses Boost).
  double lo = -40, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi);
    (1 - PnormUpper(m) < p ? lo : hi) = m;
  }
  return 0.5 * (lo + hi);
}

// "gen EXPR (i=1..n)" samples used by the Shapiro-Wilk rows.
std::vector<double> Sample(const std::map<std::string, std::string>& a) {
  const int n = std::stoi(a.at("n"));
  const std::string x = a.at("x");
  if (x.rfind("gen ", 0) != 0) return Numbers(x);
  std::vector<double> v;
  for (int i = 1; i <= n; ++i) {
    if (x.find("i^2") != std::string::npos)
      v.push_back(double(i) * i);
    else if (x.find("log(i)") != std::string::npos)
      v.push_back(std::log(double(i)));
    else if (x.find("qnorm((i-0.375)/(n+0.25))") != std::string::npos)
      v.push_back(Qnorm((i - 0.375) / (n + 0.25)));
    else if (x.find("exp(qnorm((i-0.5)/n))") != std::string::npos)
      v.push_back(std::exp(Qnorm((i - 0.5) / n)));
    else if (x.find("gen i ") != std::string::npos)
      v.push_back(i);
    else
      ADD_FAILURE() << "unknown generator " << x;
  }
  return v;
}

LongTable Groups(const std::map<std::string, std::string>& a) {
  LongTable t;
  t.key_names = {"g"};
  t.keys.assign(1, {});
  for (const char* g : {"a", "b", "c"}) {
    for (double v : Numbers(a.at(g))) {
      t.keys[0].push_back(g);
      t.y.push_back(v);
    }
  }
  return t;
}

std::vector<std::vector<double>> Matrix3(const std::string& s) {
  auto v = Numbers(s.substr(0, s.find('(')));
  return {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}};
}

double Compute(const std::string& func, const std::map<std::string, std::string>& a) {
  if (func == "ptukey_lower")
    return PtukeyLower(Num(a.at("q")), std::stoi(a.at("k")), Num(a.at("df")));
  if (func == "ptukey_upper")
    return PtukeyUpper(Num(a.at("q")), std::stoi(a.at("k")), Num(a.at("df")));
  if (func == "ptukey_exact_k2") return PtukeyLower(Num(a.at("q")), 2, Num(a.at("df")));
  if (func == "qtukey") return Qtukey(Num(a.at("p")), std::stoi(a.at("k")), Num(a.at("df")));
  if (func == "shapiro_W") return ShapiroWilk(Sample(a)).W;
  if (func == "shapiro_p") return ShapiroWilk(Sample(a)).p;
  if (func == "pf_upper") return PfUpper(Num(a.at("F")), Num(a.at("df1")), Num(a.at("df2")));
  if (func == "qf") return Qf(Num(a.at("p")), Num(a.at("df1")), Num(a.at("df2")));
  if (func == "pchisq_upper") return PchisqUpper(Num(a.at("x")), Num(a.at("df")));
  if (func == "pt_two_sided") return PtTwoSided(Num(a.at("t")), Num(a.at("df")));
  if (func == "pnorm_two_sided") return PnormTwoSided(Num(a.at("z")));
  if (func == "qt") return Qt(Num(a.at("p")), Num(a.at("df")));
  if (func.rfind("mauchly", 0) == 0 || func == "gg_epsilon" || func == "hf_epsilon") {
    const auto sp = SphericityFromLevelCovariance(Matrix3(a.at("S")), std::stoi(a.at("n")));
    if (func == "mauchly_W") return sp.W;
    if (func == "mauchly_chi2") return sp.chi2;
    if (func == "mauchly_p_firstorder") return sp.p_firstorder;
    if (func == "gg_epsilon") return sp.gg;
    return sp.hf;
  }
  if (func.rfind("kruskal", 0) == 0 || func.rfind("dunn", 0) == 0) {
    const auto kw = KruskalWallis(Groups(a), "g");
    if (func == "kruskal_H") return kw.H;
    if (func == "kruskal_p") return kw.p;
    const std::string pair = a.at("pair");
    for (const auto& d : kw.dunn)
      if (d.a + "-" + d.b == pair) return func == "dunn_z" ? d.z : d.p_adj;
  }
  ADD_FAILURE() << "no implementation for " << func;
  return NAN;
}

TEST(ReferenceVectors, EveryRowWithinItsTolerance) {
  const auto t = ReadCsv(test::DataPath("stats/vectors.csv"));
  int checked = 0;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string func = t.rows[r][t.Require("func")];
    const std::string args = t.rows[r][t.Require("args")];
    const double expected = t.Number(r, t.Require("expected"));
    const std::string ta = t.rows[r][t.Require("tol_abs")], tr = t.rows[r][t.Require("tol_rel")];
    const double got = Compute(func, Args(args));
    const double diff = std::abs(got - expected);
    SCOPED_TRACE(func + " " + args);
    if (!ta.empty()) {
      EXPECT_LE(diff, std::stod(ta)) << "got " << got << " expected " << expected;
    }
    if (!tr.empty()) {
      EXPECT_LE(diff, std::stod(tr) * std::abs(expected))
          << "got " << got << " expected " << expected;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 73);
}

TEST(Distributions, TukeyK2IsExactlyAScaledT) {
  // For two means the studentized range is sqrt(2)|T|: P(Q <= q) = 2 pt(q / sqrt 2, df) - 1.
  for (double df : {2.0, 5.0, 30.0})
    for (double q : {0.5, 2.0, 6.0})
      EXPECT_NEAR(PtukeyLower(q, 2, df), 1 - PtTwoSided(q / std::sqrt(2.0), df), 1e-11)
          << q << " " << df;
}

TEST(Distributions, LowerAndUpperTukeyTailsAddToOne) {
  for (int k : {3, 7})
    for (double q : {1.0, 3.5, 5.0})
      EXPECT_NEAR(PtukeyLower(q, k, 12) + PtukeyUpper(q, k, 12), 1.0, 1e-12);
  EXPECT_NEAR(PtukeyLower(Qtukey(0.95, 4, 20), 4, 20), 0.95, 1e-12);
}

TEST(Distributions, TabulatedFamilyAgreesWithDirectQuadrature) {
  for (int k : {2, 3, 10, 50})
    for (double df : {2.0, 9.0, 297.0, std::numeric_limits<double>::infinity()}) {
      const TukeyFamily fam(k, df);
      for (double q : {0.3, 1.5, 3.0, 5.0, 9.0, 16.0}) {
        SCOPED_TRACE(testing::Message() << "k=" << k << " df=" << df << " q=" << q);
        EXPECT_NEAR(fam.Lower(q), PtukeyLower(q, k, df), 1e-12);
        const double up = PtukeyUpper(q, k, df);
        EXPECT_LE(std::abs(fam.Upper(q) - up), 1e-9 * up + 1e-300);
      }
    }
}

}  // namespace
}  // namespace hapticlab::stats::reference_vectors_test
