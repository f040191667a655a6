#include "hapticlab/protocols/participant_code.hpp"

#include <gtest/gtest.h>

#include <regex>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::protocols::participant_code_test {
namespace {

Protocol WithPattern(const std::string& pattern) {
  Protocol p = ParseProtocol(test::ReadFile(test::DataPath("protocols/small.toml")), "s.toml");
  p.participant_code = pattern;
  return p;
}

TEST(ParticipantCode, DefaultPatternKeepsP01) {
  const Protocol p = WithPattern(Protocol{}.participant_code);
  const CodeFormat f = InferCodeFormat(p);
  EXPECT_EQ(f.prefix, "P");
  EXPECT_EQ(f.digits, 2);
  EXPECT_EQ(NextFreeCode(p, f, {}), "P01");
  EXPECT_EQ(NextFreeCode(p, f, {"P01", "P02"}), "P03");
}

TEST(ParticipantCode, InfersPrefixAndWidthOfACustomPattern) {
  struct Case {
    std::string pattern, first;
  };
  for (const auto& c : std::vector<Case>{{"^NU[0-9]{3}$", "NU001"},
                                         {"^NU\\d{4}$", "NU0001"},
                                         {"^LAB-[0-9]{2}$", "LAB-01"},
                                         {"^S[1-9][0-9]{2}$", "S100"},  // 001 refused
                                         {"XY[0-9]+", "XY01"}}) {
    const Protocol p = WithPattern(c.pattern);
    const std::string code = NextFreeCode(p, InferCodeFormat(p), {});
    EXPECT_EQ(code, c.first) << c.pattern;
    EXPECT_TRUE(std::regex_match(code, std::regex(c.pattern))) << c.pattern;
  }
}

TEST(ParticipantCode, AnOptionalLetterIsNotPartOfThePrefix) {
  // "A" is in every code, "B?" is not: the prefix stops before the quantified letter.
  const Protocol p = WithPattern("^AB?[0-9]{2}$");
  EXPECT_EQ(InferCodeFormat(p).prefix, "A");
  EXPECT_EQ(NextFreeCode(p, InferCodeFormat(p), {}), "A01");
}

TEST(ParticipantCode, APatternWithoutAFixedPrefixNeedsOne) {
  const Protocol p = WithPattern("^(NU|XY)[0-9]{3}$");
  try {
    (void)InferCodeFormat(p);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("study.participant_code"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("--prefix"), std::string::npos) << e.what();
  }
  const CodeFormat f = InferCodeFormat(p, "XY");
  EXPECT_EQ(NextFreeCode(p, f, {}), "XY001");
  EXPECT_THROW((void)InferCodeFormat(p, "QQ"), InputError);
}

}  // namespace
}  // namespace hapticlab::protocols::participant_code_test
