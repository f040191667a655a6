#include "hapticlab/protocols/protocol.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol_keys.hpp"
#include "hapticlab/test/doc_block.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::protocols::protocol_test {
namespace {

std::string Small() { return test::ReadFile(test::DataPath("protocols/small.toml")); }

TEST(Protocol, ParsesTheSmallStudy) {
  const auto p = LoadProtocol(test::DataPath("protocols/small.toml"));
  EXPECT_EQ(p.name, "test-small");
  EXPECT_EQ(p.consent_document, "test-small consent form");
  EXPECT_EQ(p.consent_version, "2026-11");
  EXPECT_EQ(p.materials.size(), 4u);
  EXPECT_EQ(p.methods.size(), 2u);
  EXPECT_TRUE(p.methods[1].vibration);  // default
  EXPECT_EQ(p.phases.size(), 3u);
  EXPECT_EQ(p.break_every_trials, 8);
}

TEST(Protocol, EveryValidationErrorNamesFileLineAndKey) {
  std::string deep_key = "a";
  for (int i = 0; i < 40; ++i) deep_key += ".a";
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"seed = 42", "seed = -3", "study.seed: expected a non-negative integer"},
      {"seed = 42", "seed = \"x\"", "study.seed: expected a non-negative integer"},
      {"criteria = [\"roughness\", \"overall\"]", "criteria = []",
       "study.criteria: needs at least one criterion"},
      {"stimulus_duration_s = 0.5", "stimulus_duration_s = -1.0", "study.stimulus_duration_s"},
      {"algorithm = \"fric2\"\nvibration", "algorithm = \"fric9\"\nvibration",
       "method[0].algorithm: expected wall, norm, fric1, fric2 or none, got 'fric9'"},
      {"name = \"Hybrid\"", "name = \"FF\"", "method[1].name: duplicate method 'FF'"},
      {"id = \"Cork\"", "id = \"Denim\"", "material[1].id: duplicate material id 'Denim'"},
      {"kind = \"training\"", "kind = \"warmup\"",
       "phase[0].kind: expected training, reference, main, staircase or quest-plus, got 'warmup'"},
      {"repetitions = 2", "repetitions = 0", "phase[2].repetitions: expected an integer 1..100"},
      {"different_pairs = 2", "different_pairs = 7", "phase[1].different_pairs: expected 0..6"},
      {"different_pairs = 2", "different_pairs = [[\"Denim\", \"Nope\"]]",
       "phase[1].different_pairs"},
      {"scheme = \"full\"", "scheme = \"random\"",
       "randomization.scheme: expected full, blocked or latin-square"},
      {"scheme = \"full\"", "scheme = \"blocked\"\nblock_by = \"material\"",
       "infeasible with no_immediate_repeat"},
      {"every_trials = 8", "every_trials = 8\nduraton_s = 3", "breaks.duraton_s: unknown key"},
      {"duration_s = 30",
       "duration_s = 30\n[analysis]\ntests = [\"lmm\"]\nlmm_formula = \"score ~ method\"",
       "analysis.lmm_formula: expected an lme4 formula"},
      {"[study]", "[studdy]", "studdy: unknown key"},
      // Range-checked before narrowing: 2^32 must not wrap to 0 ("no breaks").
      {"every_trials = 8", "every_trials = 4294967296",
       "breaks.every_trials: expected an integer 0..10000"},
      {"every_trials = 8", "every_trials = -1",
       "breaks.every_trials: expected an integer 0..10000"},
      {"seed = 42", "seed = 42\nparticipant_code = \"([A-Z\"",
       "study.participant_code: not a valid regular expression"},
      // [consent]: both keys, one line each, a name rather than a path (no user or host name).
      {"document = \"test-small consent form\"", "document = \"/home/alice/consent.pdf\"",
       "consent.document: expected the document's name or title, not an absolute path"},
      {"document = \"test-small consent form\"", "document = \"\"",
       "consent.document: expected the consent document's name or title"},
      {"version = \"2026-11\"", "versoin = \"2026-11\"", "consent.versoin: unknown key"},
      {"version = \"2026-11\"", "", "consent.version: missing"},
      {"version = \"2026-11\"", "version = 3", "consent.version: expected its version"},
      // Input limits before toml++ parses (its recursion would overflow the stack).
      {"seed = 42", "seed = 42\n" + deep_key + " = 1", "more than 32 dotted parts"},
  };
  for (const auto& c : cases) {
    std::string text = Small();
    const auto pos = text.find(c.from);
    ASSERT_NE(pos, std::string::npos) << c.from;
    text.replace(pos, c.from.size(), c.to);
    try {
      ParseProtocol(text, "bad.toml");
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(c.expect), std::string::npos) << "case '" << c.to << "' gave:\n" << msg;
      EXPECT_NE(msg.find("bad.toml:"), std::string::npos) << msg;
    }
  }
}

TEST(Protocol, ParticipantCodesFollowThePatternAndAreNeverNames) {
  const auto p = ParseProtocol(Small(), "small.toml");
  for (const char* ok : {"P07", "AB123", "SIM01", "X9999"})
    EXPECT_NO_THROW(CheckParticipantCode(p, ok)) << ok;
  for (const char* bad : {"Anna_Kowalski_19850312", "JohnSmith1985", "1985-03-12", "0151-2345678",
                          "+491512345678", "P7", "p07", "P07 ", "", "P00000"}) {
    try {
      CheckParticipantCode(p, bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      ASSERT_EQ(e.diagnostics().size(), 1U) << e.what();
      EXPECT_EQ(e.diagnostics()[0].field, "participant") << e.what();  // the CLI: --participant
    }
  }
  // A protocol may declare its own pattern.
  std::string text = Small();
  text.replace(text.find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^lab2-[0-9]{3}$\"");
  const auto q = ParseProtocol(text, "q.toml");
  EXPECT_NO_THROW(CheckParticipantCode(q, "lab2-014"));
  EXPECT_THROW(CheckParticipantCode(q, "P07"), InputError);
  // The refusal's example is one the protocol's pattern accepts, not the default's P07.
  try {
    CheckParticipantCode(q, "JohnSmith");
    ADD_FAILURE() << "accepted JohnSmith";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("e.g. lab2-001"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("P07"), std::string::npos) << msg;
  }
}

TEST(Protocol, CodePatternsMatchInLinearTimeAndNeverAdmitNames) {
  // std::regex backtracked 2^31 times here (437 s); RE2 does not backtrack.
  std::string text = Small();
  text.replace(text.find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^(A|A)*B$\"");
  const auto p = ParseProtocol(text, "p.toml");
  EXPECT_THROW(CheckParticipantCode(p, std::string(31, 'A') + "C"), InputError);
  // A pattern that admits anything: the code's own shape still refuses names and dates.
  text = Small();
  text.replace(text.find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^[A-Za-z_0-9-]+$\"");
  const auto q = ParseProtocol(text, "q.toml");
  EXPECT_NO_THROW(CheckParticipantCode(q, "lab2-014"));
  for (const char* bad : {"Anna_Kowalski_19850312", "1985-03-12", "JohnSmith1985"})
    EXPECT_THROW(CheckParticipantCode(q, bad), InputError) << bad;
  // Back-references and look-arounds are not RE2 syntax: refused when the protocol is read.
  for (const char* pattern : {"^(A)\\1$", "^(?=P)P[0-9]+$"}) {
    std::string why;
    EXPECT_FALSE(ValidCodePattern(pattern, &why)) << pattern;
    EXPECT_NE(why.find("RE2"), std::string::npos) << why;
  }
}

TEST(Protocol, SizesAndNumbersAreBoundedWhenRead) {
  auto problems = [](const std::string& text) {
    try {
      ParseProtocol(text, "b.toml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string small = Small();
  const std::string head = small.substr(0, small.find("[[material]]")),
                    tail = small.substr(small.find("[[method]]"));
  std::string many;
  for (std::size_t i = 0; i <= kMaxMaterials; ++i)
    many += fmt::format("[[material]]\nid = \"m{}\"\n", i);
  EXPECT_NE(problems(head + many + tail).find("1001 entries; at most 1000"), std::string::npos);
  // 1000 materials x 2 methods x 11 repetitions: more trials than a plan may hold.
  many.clear();
  for (std::size_t i = 0; i < kMaxMaterials; ++i)
    many += fmt::format("[[material]]\nid = \"m{}\"\n", i);
  std::string big = head + many + tail;
  big.replace(big.find("repetitions = 2"), 15, "repetitions = 11");
  EXPECT_NE(problems(big).find("more than the 20000 allowed"), std::string::npos) << problems(big);
  for (const char* level : {"inf", "180.0", "-5.0"})
    EXPECT_NE(problems(small + "\n[masking_noise]\nlevel_dB = " + level + "\n")
                  .find("masking_noise.level_dB"),
              std::string::npos)
        << level;
  for (const char* seconds : {"1e300", "nan", "-1.0"}) {
    std::string text = small;
    text.replace(text.find("duration_s = 30"), 15, std::string("duration_s = ") + seconds);
    EXPECT_NE(problems(text).find("breaks.duration_s"), std::string::npos) << seconds;
  }
}

TEST(Protocol, ReportsAllProblemsAtOnce) {
  std::string text = Small();
  text.replace(text.find("seed = 42"), 9, "seed = -1");
  text.replace(text.find("repetitions = 2"), 15, "repetitions = 0");
  try {
    ParseProtocol(text, "bad.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_GE(e.diagnostics().size(), 2u) << e.what();
  }
}

TEST(Protocol, InfeasibleNoRepeatIsAnErrorBeforeAnySession) {
  // One material, two methods, no immediate repeats: impossible.
  const std::string text = R"([study]
name = "x"
seed = 1
criteria = ["overall"]
[[material]]
id = "Denim"
[[method]]
name = "a"
algorithm = "fric2"
[[method]]
name = "b"
algorithm = "norm"
[[phase]]
kind = "main"
)";
  try {
    ParseProtocol(text, "one.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot avoid immediate repeats"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("one.toml:13"), std::string::npos) << e.what();
  }
}

TEST(Protocol, TitleAndSphericityCorrectionHaveDefaultsAndAfexsNames) {
  const auto p = ParseProtocol(Small(), "small.toml");
  EXPECT_EQ(p.title, p.name);     // no [study] title: the name
  EXPECT_EQ(p.correction, "GG");  // afex's default
  std::string text = Small();
  text.replace(text.find("[study]\n"), 8, "[study]\ntitle = \"A small study\"\n");
  text += "\n[analysis]\ntests = [\"rm-anova\"]\ncorrection = \"HF\"\n";
  const auto q = ParseProtocol(text, "q.toml");
  EXPECT_EQ(q.title, "A small study");
  EXPECT_EQ(q.correction, "HF");
  const std::string bad = Small() + "\n[analysis]\ntests = [\"rm-anova\"]\ncorrection = \"gg\"\n";
  try {
    ParseProtocol(bad, "bad.toml");
    FAIL() << "a correction by another name was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("analysis.correction"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"GG\""), std::string::npos) << e.what();
  }
}

// docs/formats.md's key tables are printed from the field tables the parser reads through.
TEST(ProtocolDocs, FormatsKeyTablesAreTheParsersTables) {
  EXPECT_EQ(test::CheckGeneratedDocBlock("docs/formats.md", "protocol keys", ProtocolKeyTables()),
            "");
}

// The shipped protocols (studies/) parse as they did before the field tables.
TEST(ProtocolDocs, EveryShippedProtocolParses) {
  int parsed = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(
           std::filesystem::path(HL_SOURCE_DIR) / "studies")) {
    if (e.path().extension() != ".toml") continue;
    const std::string text = test::ReadFile(e.path().string());
    if (text.find("[study]") == std::string::npos) continue;  // profiles, models
    EXPECT_NO_THROW((void)ParseProtocol(text, e.path().string())) << e.path();
    ++parsed;
  }
  EXPECT_GE(parsed, 5);
}

// Every number is checked finite and within its range when read (issue #34's inputs).
TEST(Protocol, RefusesNonFiniteAndOutOfRangeNumbersNamingLineAndField) {
  const std::string small = Small();
  struct Case {
    std::string from, to, want;
  };
  for (const Case& c : std::vector<Case>{
           {"[breaks]", "[masking_noise]\nlevel_dB = inf\n\n[breaks]",
            "masking_noise.level_dB: expected a number in [0, 100] dB, got inf"},
           {"duration_s = 30", "duration_s = 1e300",
            "breaks.duration_s: expected a number in [0, 3600] s, got 1e+300"},
           {"stimulus_duration_s = 0.5", "stimulus_duration_s = nan",
            "study.stimulus_duration_s: expected a number in (0, 600] s, got nan"},
           {"stimulus_duration_s = 0.5", "stimulus_duration_s = \"2\"",
            "study.stimulus_duration_s: expected a number in (0, 600] s"},
       }) {
    std::string text = small;
    ASSERT_NE(text.find(c.from), std::string::npos) << c.from;
    text.replace(text.find(c.from), c.from.size(), c.to);
    try {
      (void)ParseProtocol(text, "bad.toml");
      ADD_FAILURE() << c.to << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.want), std::string::npos) << e.what();
      // Every problem names the file and a line.
      EXPECT_NE(std::string(e.what()).find("bad.toml:"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace hapticlab::protocols::protocol_test
