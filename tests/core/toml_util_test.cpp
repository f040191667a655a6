// ParseTomlFile / ParseTomlText: the one TOML entry point of the readers of user files.

#include "hapticlab/core/toml_util.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/fields.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab::toml_util_test {
namespace {

// The InputError the parser throws for `text` ("" when it parses).
InputError Refusal(const std::string& text) {
  try {
    (void)ParseTomlText(text, "x.toml");
  } catch (const InputError& e) {
    return e;
  }
  return InputError("", 0, "", "");
}

TEST(ParseToml, ValidTextGivesTheTable) {
  const toml::table t = ParseTomlText("[a]\nb = 2.5\nc = \"x\"\n", "x.toml");
  EXPECT_DOUBLE_EQ(t["a"]["b"].value_or(0.0), 2.5);
  EXPECT_EQ(t["a"]["c"].value_or(std::string()), "x");
}

TEST(ParseToml, SyntaxErrorNamesFileLineAndColumn) {
  // Line 3, column 5: the value after '=' is missing (toml++ reports where it stopped).
  const InputError e = Refusal("[a]\nb = 1\nc = \n");
  ASSERT_EQ(e.diagnostics().size(), 1U);
  const Diagnostic& d = e.diagnostics()[0];
  EXPECT_EQ(d.file, "x.toml");
  EXPECT_EQ(d.line, 3);
  EXPECT_NE(d.message.find("column "), std::string::npos) << d.message;
  // A key defined twice: reported on the second definition's line.
  EXPECT_EQ(Refusal("x = 1\n\nx = 2\n").diagnostics().at(0).line, 3);
}

TEST(ParseToml, LimitsAreCheckedBeforeTomlPlusPlus) {
  std::string key = "a";
  for (int i = 0; i < 40; ++i) key += ".a";
  const InputError e = Refusal("n = 1\n" + key + " = 1\n");
  ASSERT_FALSE(e.diagnostics().empty());
  EXPECT_EQ(e.diagnostics()[0].line, 2);
  EXPECT_NE(std::string(e.what()).find("dotted parts"), std::string::npos) << e.what();
}

TEST(ParseToml, FileIsReadAndAMissingFileIsNamed) {
  const auto dir = std::filesystem::temp_directory_path() / "hl_toml_util_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "ok.toml").string();
  std::ofstream(path) << "[s]\nk = 3\n";
  EXPECT_EQ(ParseTomlFile(path)["s"]["k"].value_or(0), 3);
  const std::string missing = (dir / "none.toml").string();
  try {
    (void)ParseTomlFile(missing, "observer file");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("observer file"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// Declared field tables (core/fields.hpp): one table gives the reader, its messages, the
// validator of structs built in code and the docs' key table.
struct Toy {
  std::string name;
  double duration_s = 2;
  int count = 1;
  bool on = true;
  std::vector<double> gains;
  int mode = 0;
};

std::span<const fields::Field<Toy>> ToyFields() {
  using fields::Type;
  static const fields::Field<Toy> kFields[] = {
      {.key = "name",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Toy, name),
       .required = true,
       .doc = "what it is called"},
      {.key = "duration_s",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(Toy, duration_s),
       .range = fields::OpenClosed(0, 600),
       .unit = "s",
       .doc = "how long"},
      {.key = "count",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(Toy, count),
       .range = {1, 100},
       .doc = "how many"},
      {.key = "on", .type = Type::kBool, .ref = HL_FIELD_REF(Toy, on), .doc = "a|b switch"},
      {.key = "gains",
       .type = Type::kNumbers,
       .ref = HL_FIELD_REF(Toy, gains),
       .range = {0, 10},
       .doc = "per channel"},
      {.key = "mode",
       .type = Type::kChoice,
       .ref = +[](Toy& t, std::size_t i) { t.mode = static_cast<int>(i); },
       .doc = "how",
       .choices = "fast|slow",
       .chosen = +[](const Toy& t) { return static_cast<std::size_t>(t.mode); }},
  };
  return kFields;
}

// Reads `text`'s [toy] table; the problems, one per line ("" when none).
std::string ReadToy(const std::string& text, Toy* toy) {
  const toml::table doc = ParseTomlText(text, "t.toml");
  Diagnostics d;
  fields::FieldReader(*doc["toy"].as_table(), "toy", "t.toml", &d).Read(ToyFields(), toy);
  return d.ToString();
}

TEST(Fields, ReadsEveryDeclaredKeyIntoItsMember) {
  Toy t;
  EXPECT_EQ(ReadToy("[toy]\nname = \"a\"\nduration_s = 600\ncount = 7\non = false\n"
                    "gains = [0, 2.5]\nmode = \"slow\"\n",
                    &t),
            "");
  EXPECT_EQ(t.name, "a");
  EXPECT_EQ(t.duration_s, 600);
  EXPECT_EQ(t.count, 7);
  EXPECT_FALSE(t.on);
  EXPECT_EQ(t.gains, (std::vector<double>{0, 2.5}));
  EXPECT_EQ(t.mode, 1);
}

TEST(Fields, RefusesNonFiniteOutOfRangeWrongTypeUnknownAndMissing) {
  Toy t;
  const std::string out = ReadToy(
      "[toy]\nduration_s = inf\ncount = 4294967297\non = 1\ngains = [1, nan, 11]\n"
      "mode = \"medium\"\nnmae = \"x\"\n",
      &t);
  for (const char* want : {
           "t.toml:1: toy.name: missing; expected a string",
           "t.toml:2: toy.duration_s: expected a number in (0, 600] s, got inf",
           "t.toml:3: toy.count: expected an integer 1..100, got 4294967297",
           "t.toml:4: toy.on: expected true or false",
           "t.toml:5: toy.gains[1]: expected a number in [0, 10]",
           "t.toml:5: toy.gains[2]: expected a number in [0, 10], got 11",
           "t.toml:6: toy.mode: expected fast or slow, got 'medium'",
           "t.toml:7: toy.nmae: unknown key (a typo?)",
       })
    EXPECT_NE(out.find(want), std::string::npos) << want << "\n" << out;
  // Refused values leave the members as they were.
  EXPECT_EQ(t.duration_s, 2);
  EXPECT_EQ(t.count, 1);
  EXPECT_TRUE(t.gains.empty());
  EXPECT_EQ(ReadToy("[toy]\nname = \"a\"\nduration_s = 1e300\n", &t).find("got 1e+300") ==
                std::string::npos,
            false);
}

TEST(Fields, CheckFieldsValidatesAStructBuiltInCode) {
  Toy t;
  t.duration_s = 0;  // the range is open at 0
  t.gains = {1, 1e100};
  Diagnostics d;
  fields::CheckFields(ToyFields(), t, "toy", "fit", &d);
  const std::string out = d.ToString();
  EXPECT_NE(out.find("fit: toy.duration_s: expected a number in (0, 600] s, got 0"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("toy.gains: expected an array of numbers, each in [0, 10], got 1e+100"),
            std::string::npos)
      << out;
  EXPECT_EQ(d.size(), 2U);
}

TEST(Fields, MarkdownTableShowsTypesRangesUnitsAndDefaultsFromTheStruct) {
  const std::string md = fields::FieldsMarkdown(ToyFields());
  EXPECT_NE(md.find("| `name` | a string |  | required | what it is called |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("| `duration_s` | a number in (0, 600] | s | 2 | how long |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| `count` | an integer 1..100 |  | 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `on` | true or false |  | true | a\\|b switch |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `mode` | fast or slow |  | \"fast\" | how |"), std::string::npos) << md;
}

}  // namespace
}  // namespace hapticlab::toml_util_test
