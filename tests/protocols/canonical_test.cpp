#include "hapticlab/protocols/canonical.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::protocols::canonical_test {
namespace {

std::string Small() { return test::ReadFile(test::DataPath("protocols/small.toml")); }

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

// The form written out by hand from the TOML and JSON specifications: sorted keys, no
// whitespace, 2.0 spelled as 2, nested tables and arrays of tables.
TEST(CanonicalForm, IsSortedCompactJsonOfTheDocument) {
  const std::string text =
      "# a comment\n"
      "[study]\n"
      "seed = 7\n"
      "name = \"a \\\"q\\\"\"   # trailing comment\n"
      "scale = [0, 100.0]\n"
      "x = 0.25\n"
      "[[phase]]\n"
      "repetitions = 3\n"
      "kind = 'main'\n"
      "[breaks]\n"
      "on = true\n";
  EXPECT_EQ(CanonicalFormOfText(text, "t.toml"),
            R"({"breaks":{"on":true},"phase":[{"kind":"main","repetitions":3}],)"
            R"("study":{"name":"a \"q\"","scale":[0,100],"seed":7,"x":0.25}})");
}

TEST(CanonicalForm, CommentsFormattingKeyOrderAndNumberSpellingDoNotChangeIt) {
  const std::string base = Small();
  std::string edited = "# an added comment line\n" + base;
  edited = Replace(edited, "seed = 42", "seed    =    42   # the study seed");
  edited = Replace(edited, "stimulus_duration_s = 0.5", "stimulus_duration_s = 5e-1");
  edited = Replace(edited, "name = \"test-small\"\nseed", "seed");  // move name below
  edited = Replace(edited, "profiles = \"profiles.toml\"",
                   "profiles = 'profiles.toml'\nname = \"test-small\"");
  edited = Replace(edited, "duration_s = 30", "duration_s = 30.0");
  ASSERT_NE(edited, base);
  EXPECT_EQ(CanonicalFormOfText(edited, "e.toml"), CanonicalFormOfText(base, "b.toml"));
  EXPECT_TRUE(CanonicalDifferences(base, edited).empty());
  const Protocol p = ParseProtocol(base, "b.toml");
  EXPECT_EQ(CanonicalForm(p), CanonicalFormOfText(base, "x"));
}

TEST(CanonicalDifferences, NameTheKeyTheOldAndTheNewValue) {
  const std::string base = Small();
  const auto changes =
      CanonicalDifferences(base, Replace(base, "repetitions = 2", "repetitions = 3"));
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].key, "phase[2].repetitions");
  EXPECT_EQ(changes[0].old_value, "2");
  EXPECT_EQ(changes[0].new_value, "3");
  EXPECT_EQ(changes[0].Describe(), "phase[2].repetitions: 2 -> 3");
}

TEST(CanonicalDifferences, AddedRemovedAndArrayValues) {
  const std::string base = Small();
  std::string edited = Replace(base, "criteria = [\"roughness\", \"overall\"]",
                               "criteria = [\"roughness\", \"friction\"]");
  edited = Replace(edited, "[[material]]\nid = \"Towel\"\n", "");
  edited = Replace(edited, "scheme = \"full\"", "scheme = \"full\"\nbalance_sides = false");
  const auto changes = CanonicalDifferences(base, edited);
  ASSERT_EQ(changes.size(), 3u);
  EXPECT_EQ(changes[0].Describe(), "material[3]: {\"id\":\"Towel\"} -> (absent)");
  EXPECT_EQ(changes[1].Describe(), "randomization.balance_sides: (absent) -> false");
  EXPECT_EQ(changes[2].Describe(),
            "study.criteria: [\"roughness\",\"overall\"] -> [\"roughness\",\"friction\"]");
  EXPECT_NE(CanonicalFormOfText(base, "a"), CanonicalFormOfText(edited, "b"));
}

TEST(CanonicalForm, InvalidTomlIsAnInputErrorNamingTheFile) {
  try {
    (void)CanonicalFormOfText("[study\nname = 1", "bad.toml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::protocols::canonical_test
