// Input limits checked before toml++ parses a text, the size limit of ReadTextFile, and
// WriteTextFile's bytes and errors.

#include "hapticlab/core/io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::io_test {
namespace {

std::string Repeat(const std::string& s, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

// The message of the InputError CheckTomlLimits throws ("" when it accepts the text).
std::string Refusal(const std::string& text) {
  try {
    CheckTomlLimits(text, "x.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TomlLimits, DeepDottedKeysAreRefusedWithFileLineAndKey) {
  // 50,000 parts overflowed toml++'s stack; here they are refused before it runs.
  const std::string msg = Refusal("[study]\nname = \"x\"\n\na" + Repeat(".a", 50000) + " = 1\n");
  EXPECT_NE(msg.find("x.toml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("more than 32 dotted parts"), std::string::npos) << msg;
  EXPECT_NE(Refusal("[a" + Repeat(".a", 40) + "]\n").find("dotted parts"),
            std::string::npos);  // table header
  EXPECT_NE(Refusal("[[a" + Repeat(".a", 40) + "]]\n").find("dotted parts"),
            std::string::npos);  // array of tables
  EXPECT_NE(Refusal("t = { x = 1, a" + Repeat(".a", 40) + " = 2 }\n").find("dotted parts"),
            std::string::npos);
  EXPECT_EQ(Refusal("a" + Repeat(".a", 31) + " = 1\n"), "");  // 32 parts: the limit itself
}

TEST(TomlLimits, LongKeysAndDeepNestingAreRefused) {
  EXPECT_NE(Refusal(std::string(2000, 'k') + " = 1\n").find("longer than 1024"), std::string::npos);
  EXPECT_NE(Refusal("\"" + std::string(2000, 'k') + "\" = 1\n").find("longer than 1024"),
            std::string::npos);
  EXPECT_NE(Refusal("a = " + Repeat("[", 40) + Repeat("]", 40) + "\n").find("nest deeper than 32"),
            std::string::npos);
  EXPECT_NE(
      Refusal("a = " + Repeat("{b = ", 40) + "1" + Repeat("}", 40) + "\n").find("nest deeper"),
      std::string::npos);
  EXPECT_EQ(Refusal("a = " + Repeat("[", 32) + Repeat("]", 32) + "\n"), "");
}

TEST(TomlLimits, StringsCommentsAndNumbersDoNotCount) {
  // Dots and brackets inside values, strings and comments are not keys or nesting.
  const std::string ok = "name = \"" + Repeat("a.", 100) +
                         "[[[[\"\n"
                         "lit = '" +
                         Repeat("{.", 100) +
                         "'\n"
                         "ml = \"\"\"\n" +
                         Repeat("x.y.z [ { \\\" \n", 50) +
                         "\"\"\"\n"
                         "mll = '''\n" +
                         Repeat("a.b.c [[ ''\n", 50) +
                         "'''\n"
                         "v = [" +
                         Repeat("1.5, ", 2000) +
                         "2.5]\n"
                         "# a" +
                         Repeat(".a", 100) +
                         " [[[[[[[[\n"
                         "\"quoted.key.with.dots\" = 1\n"
                         "m = [\n  [1.0, 2.0],\n  [3.0, 4.0],\n]\n"
                         "t = { x = 1.5, y = \"a.b.c\" }\n";
  EXPECT_EQ(Refusal(ok), "");
  // Line numbers count the lines of multi-line strings.
  const std::string msg = Refusal("s = \"\"\"\n1\n2\n\"\"\"\na" + Repeat(".a", 40) + " = 1\n");
  EXPECT_NE(msg.find("x.toml:5:"), std::string::npos) << msg;
}

TEST(ReadTextFile, RefusesFilesLargerThanTheLimit) {
  test::TempDir dir;
  test::WriteFile(dir.File("big.txt"), std::string(5000, 'x'));
  EXPECT_EQ(ReadTextFile(dir.File("big.txt"), "file", 5000).size(), 5000u);
  try {
    ReadTextFile(dir.File("big.txt"), "file", 4999);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("big.txt"), std::string::npos);
  }
}

TEST(ReadTextFile, AFolderIsNamedAsOneNotReadAsAnEmptyFile) {
  test::TempDir dir;
  try {
    (void)ReadTextFile(dir.path(), "protocol");
    ADD_FAILURE() << "a folder was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a folder, not a file: protocol expected"),
              std::string::npos)
        << e.what();
  }
}

// The message of the std::runtime_error WriteTextFile throws ("" when it succeeds).
std::string WriteFailure(const std::string& path, const std::string& text) {
  try {
    WriteTextFile(path, text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(WriteTextFile, WritesTheBytesAsGivenAndReplacesTheOldFile) {
  test::TempDir dir;
  const std::string path = dir.File("out.txt");
  test::WriteFile(path, std::string(100, 'o'));  // longer than what replaces it
  const std::string bytes("a,b\r\n\0tail\n", 11);
  ASSERT_EQ(WriteFailure(path, bytes), "");
  EXPECT_EQ(test::ReadFile(path), bytes);  // truncated, CR and NUL kept
}

TEST(WriteTextFile, FailuresNameTheFile) {
  test::TempDir dir;
  const std::string missing_dir = dir.File("no/such/dir/x.toml");
  EXPECT_EQ(WriteFailure(missing_dir, "x"), missing_dir + ": cannot write");
  // A full disk: /dev/full accepts the open and fails the write.
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  EXPECT_EQ(WriteFailure("/dev/full", std::string(1 << 16, 'x')), "/dev/full: write failed");
}

}  // namespace
}  // namespace hapticlab::io_test
