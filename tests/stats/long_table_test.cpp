// Long-format tables (long_table.cpp): reading with filters and missing values, cell means
// against R's aggregate(), and errors that name the file, line and column.

#include "hapticlab/stats/long_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::long_table_test {
namespace {

constexpr const char* kCsv =
    "participant,method,material,score,note\n"
    "P1,A,Cork,10,x\n"
    "P1,A,Cork,14,\n"
    "P1,B,Cork,20,x\n"
    "P2,A,Denim,7.5,x\n"
    "P2,B,Denim,9,x\n"
    "P2,B,Denim,NA,skip\n"
    "P1,B,Denim,30,x\n";

std::string Write(const test::TempDir& dir, const std::string& name, const std::string& text) {
  auto path = dir.File(name);
  std::ofstream(path) << text;
  return path;
}

TEST(LongTable, CellMeansMatchRsAggregate) {
  test::TempDir dir;
  const auto path = Write(dir, "t.csv", kCsv);
  const auto t = ReadLongCsv(path, "score", {"participant", "method"}, false,
                             {.not_equal = {{"note", "skip"}}});
  ASSERT_EQ(t.rows(), 6u);
  EXPECT_EQ(t.lines, (std::vector<std::size_t>{2, 3, 4, 5, 6, 8}));  // line 7 filtered out
  // R 4.2.2: d <- read.csv(...); d <- d[d$note != "skip", ];
  // aggregate(score ~ participant + method, d, mean): P1 A 12, P2 A 7.5, P1 B 25, P2 B 9.
  const std::map<std::pair<std::string, std::string>, double> r = {
      {{"P1", "A"}, 12.0}, {{"P2", "A"}, 7.5}, {{"P1", "B"}, 25.0}, {{"P2", "B"}, 9.0}};
  const auto m = t.Average({"participant", "method"});
  ASSERT_EQ(m.rows(), r.size());
  const auto p = m.Key("participant"), k = m.Key("method");
  for (std::size_t i = 0; i < m.rows(); ++i) {
    const std::pair<std::string, std::string> cell{m.keys[p][i], m.keys[k][i]};
    ASSERT_TRUE(r.count(cell)) << cell.first << " " << cell.second;
    EXPECT_DOUBLE_EQ(m.y[i], r.at(cell)) << cell.first << " " << cell.second;
    if (i > 0) {  // sorted by the combination
      EXPECT_LT(std::make_pair(m.keys[p][i - 1], m.keys[k][i - 1]), cell);
    }
  }
  EXPECT_THROW(t.Where({{"material", "Denim"}}), InputError);  // not a kept key column
}

TEST(LongTable, MissingResponsesAreErrorsUnlessAllowed) {
  test::TempDir dir;
  const auto path = Write(dir, "t.csv", kCsv);
  try {
    ReadLongCsv(path, "score", {"participant"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u) << e.what();
    const auto& d = e.diagnostics()[0];
    EXPECT_EQ(d.file, path);
    EXPECT_EQ(d.line, 7);  // the NA
    EXPECT_EQ(d.field, "score");
  }
  const auto t = ReadLongCsv(path, "score", {"participant", "material"}, true);
  ASSERT_EQ(t.rows(), 7u);
  EXPECT_TRUE(std::isnan(t.y[5]));
  EXPECT_EQ(t.Levels("material"), (std::vector<std::string>{"Cork", "Denim"}));
  EXPECT_EQ(t.Where({{"material", "Denim"}, {"participant", "P2"}}).rows(), 3u);
}

TEST(LongTable, EmptyKeyCellsAndUnknownColumnsAreNamed) {
  test::TempDir dir;
  const auto path = Write(dir, "k.csv", "participant,score\nP1,1\n,2\n");
  try {
    ReadLongCsv(path, "score", {"participant"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u) << e.what();
    const auto& d = e.diagnostics()[0];
    EXPECT_EQ(d.file, path);
    EXPECT_EQ(d.line, 3);
    EXPECT_EQ(d.field, "participant");
  }
  EXPECT_THROW(ReadLongCsv(path, "rating", {"participant"}), InputError);
  EXPECT_EQ(SplitList("a,,b,c,"), (std::vector<std::string>{"a", "b", "c"}));
}

}  // namespace
}  // namespace hapticlab::stats::long_table_test
