// NIST StRD certified one-way ANOVA (a second oracle, independent of R).

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::nist_anova_test {
namespace {

// Log relative error: the number of correct significant digits (NIST's measure).
double Lre(double got, double want) { return -std::log10(std::abs(got - want) / std::abs(want)); }

TEST(NistAnova, SiRstvCertifiedValues) {
  const auto t = ReadLongCsv(test::DataPath("nist/SiRstv.csv"), "resistance", {"instrument"});
  const auto r = OneWayAnova(t, "instrument");
  EXPECT_EQ(r.df_between, 4);
  EXPECT_EQ(r.df_within, 20);
  // The data carry 7 significant digits near 196; a centred two-pass computation keeps
  // at least 10 correct digits of each certified value.
  constexpr double kMinDigits = 10;
  EXPECT_GE(Lre(r.SS_between, 5.11462616000000E-02), kMinDigits);
  EXPECT_GE(Lre(r.MS_between, 1.27865654000000E-02), kMinDigits);
  EXPECT_GE(Lre(r.SS_within, 2.16636560000000E-01), kMinDigits);
  EXPECT_GE(Lre(r.MS_within, 1.08318280000000E-02), kMinDigits);
  EXPECT_GE(Lre(r.F, 1.18046237440255E+00), kMinDigits);
  EXPECT_GE(Lre(r.r_squared, 1.90999039051129E-01), kMinDigits);
  EXPECT_GE(Lre(r.residual_sd, 1.04076068334656E-01), kMinDigits);
}

}  // namespace
}  // namespace hapticlab::stats::nist_anova_test
