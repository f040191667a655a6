#include "hapticlab/core/csv.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::csv_test {
namespace {

TEST(Csv, ParsesCommentsMetadataHeaderAndQuotedCells) {
  const auto t = ParseCsv(
      "# hapticlab-measurement v1\n# material: Denim\n"
      "a,b,c\n1,\"x, y\",\"he said \"\"hi\"\"\"\n\n2,z,3\n",
      "m.csv");
  EXPECT_EQ(t.metadata.at("material"), "Denim");
  ASSERT_EQ(t.header.size(), 3u);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0][1], "x, y");
  EXPECT_EQ(t.rows[0][2], "he said \"hi\"");
  EXPECT_EQ(t.row_lines[1], 6);
  EXPECT_DOUBLE_EQ(t.Number(1, 2), 3.0);
}

TEST(Csv, ErrorsNameFileLineAndColumn) {
  const auto t = ParseCsv("speed_mps,force_N\n0.1,abc\n", "f.csv");
  try {
    t.Number(0, 1);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "f.csv:2: force_N: expected a number, got 'abc'");
  }
  EXPECT_THROW(ParseCsv("a,b\n1,2,3\n", "g.csv"), InputError);
  EXPECT_THROW(t.Require("missing"), InputError);
}

TEST(Csv, EscapeRoundTrips) {
  const std::string cell = "a,\"b\"";
  const auto t = ParseCsv("h\n" + CsvEscape(cell) + "\n", "x");
  EXPECT_EQ(t.rows[0][0], cell);
}

}  // namespace
}  // namespace hapticlab::csv_test

namespace hapticlab::csv_test {
namespace {

TEST(Csv, AUtf8ByteOrderMarkIsNotPartOfTheFirstColumn) {
  // Spreadsheet exports start with EF BB BF; the first column must still be found by name.
  const auto t = ParseCsv("\xEF\xBB\xBFt_s,acc_mps2\n0,1.5\n", "bom.csv");
  EXPECT_EQ(t.header[0], "t_s");
  EXPECT_EQ(t.Require("t_s"), 0u);
  EXPECT_DOUBLE_EQ(t.Number(0, t.Require("acc_mps2")), 1.5);
  const auto m = ParseCsv("\xEF\xBB\xBF# material: Denim\nt_s\n0\n", "bom2.csv");
  EXPECT_EQ(m.metadata.at("material"), "Denim");
}

}  // namespace
}  // namespace hapticlab::csv_test
