// ParseTomlFile / ParseTomlText: the one TOML entry point of the readers of user files.

#include "hapticlab/core/toml_util.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab {
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

}  // namespace
}  // namespace hapticlab
