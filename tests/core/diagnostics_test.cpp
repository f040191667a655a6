#include "hapticlab/core/diagnostics.hpp"

#include <gtest/gtest.h>

namespace hapticlab::diagnostics_test {
namespace {

TEST(Diagnostics, FormatsFileLineFieldAndMessageOmittingEmptyParts) {
  EXPECT_EQ((Diagnostic{"a.toml", 12, "trials", "expected an integer >= 1"}).ToString(),
            "a.toml:12: trials: expected an integer >= 1");
  EXPECT_EQ((Diagnostic{"a.toml", 0, "trials", "missing"}).ToString(), "a.toml: trials: missing");
  EXPECT_EQ((Diagnostic{"a.toml", 3, "", "bad TOML"}).ToString(), "a.toml:3: bad TOML");
  EXPECT_EQ((Diagnostic{"", 0, "", "just a message"}).ToString(), "just a message");
}

TEST(Diagnostics, CollectsEveryProblemAndThrowsOnceWithAllOfThem) {
  Diagnostics d;
  EXPECT_NO_THROW(d.ThrowIfAny());
  d.Add("p.toml", 4, "seed", "expected an integer");
  d.Add("p.toml", 9, "phase.trials", "expected >= 1");
  EXPECT_EQ(d.size(), 2u);
  try {
    d.ThrowIfAny();
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 2u);
    EXPECT_EQ(e.diagnostics()[1].line, 9);
    EXPECT_EQ(e.diagnostics()[1].field, "phase.trials");
    EXPECT_STREQ(e.what(),
                 "p.toml:4: seed: expected an integer\np.toml:9: phase.trials: expected >= 1");
  }
}

TEST(Diagnostics, KeepsTheFirstHundredProblemsAndSaysThereAreMore) {
  Diagnostics d;
  for (int i = 1; i <= 100000; ++i) d.Add("p.toml", i, "material", "bad");
  ASSERT_EQ(d.size(), 101u);  // a hostile file cannot grow the list (or the message)
  EXPECT_EQ(d.items()[99].line, 100);
  EXPECT_NE(d.items()[100].message.find("and more problems"), std::string::npos);
  EXPECT_LT(d.ToString().size(), 5000u);
}

TEST(Diagnostics, ASingleInputErrorCarriesItsDiagnostic) {
  const InputError e("<command line>", 0, "shard", "expected i/N with 0 <= i < N");
  ASSERT_EQ(e.diagnostics().size(), 1u);
  EXPECT_EQ(e.diagnostics()[0].file, "<command line>");
  EXPECT_STREQ(e.what(), "<command line>: shard: expected i/N with 0 <= i < N");
}

}  // namespace
}  // namespace hapticlab::diagnostics_test
