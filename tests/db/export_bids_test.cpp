// The BIDS export (db/src/export_bids.cpp): the dataset's files and names, the behavioural
// table in plan order, physio recordings read back through zlib with their gaps as n/a and
// their sidecars' units, the protocol with its hash, and the label collision refused. (The
// official bids-validator checks datasets written through the CLI in
// tests/apps/cmd_export_test.cpp, and InterchangeRecord's in export_xdf_test.cpp.)

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/interchange.hpp"
#include "hapticlab/test/bids.hpp"
#include "hapticlab/test/test_util.hpp"
#include "interchange_record.hpp"

namespace hapticlab::db::export_bids_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::vector<std::string>> Tsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::istringstream l(line);
    for (std::string c; std::getline(l, c, '\t');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

TEST(ExportBids, DatasetLayoutTablesAndRecordings) {
  test::TempDir dir;
  Database d(dir.File("b.db"));
  test_record::Fill(d);
  // A code reserved by `participant new` (no session) has no data: not a BIDS subject.
  d.AddParticipant({.study_id = d.Studies()[0].id, .code = "P02", .index = 1});
  const std::string ds = dir.File("bids");
  const auto files = ExportBids(d, ds);
  EXPECT_EQ(json::parse(test::ReadFile(ds + "/dataset_description.json"))["BIDSVersion"], "1.9.0");
  EXPECT_TRUE(fs::exists(ds + "/README"));
  // Labels are letters and digits; the code itself is kept beside the label.
  EXPECT_EQ(test::ReadFile(ds + "/participants.tsv"),
            "participant_id\tcode\tstudy\tplan_index\nsub-P01\tP-01\tTwo Words\t0\n");

  const std::string beh = ds + "/sub-P01/ses-1/beh/sub-P01_ses-1_task-TwoWords";
  const auto rows = Tsv(test::ReadFile(beh + "_beh.tsv"));
  ASSERT_EQ(rows.size(), 3u);  // header + one rating per completed trial
  const auto col = [&](const std::string& name) {
    for (std::size_t i = 0; i < rows[0].size(); ++i)
      if (rows[0][i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return std::size_t{0};
  };
  EXPECT_EQ(rows[1][col("trial")], "1");  // plan index 0: the plan's trial 1
  EXPECT_EQ(rows[1][col("material")], "Cork");
  EXPECT_EQ(rows[1][col("score")], "60");
  EXPECT_EQ(rows[1][col("response_time")], "0.5");
  EXPECT_EQ(rows[2][col("left")], "virtual:Denim");
  EXPECT_EQ(rows[2][col("score")], "30");
  for (const auto& r : rows) EXPECT_EQ(r.size(), rows[0].size());
  // Every column of the table is described in the sidecar.
  const auto sidecar = json::parse(test::ReadFile(beh + "_beh.json"));
  for (const auto& c : rows[0]) EXPECT_TRUE(sidecar.contains(c)) << c;

  // Trial B (run 2): 2 samples, 2 dropped (n/a at 100 Hz), 2 more.
  EXPECT_EQ(test::Gunzip(beh + "_run-2_recording-leftforce_physio.tsv.gz"),
            "10\t0.5\n11\t0.25\nn/a\tn/a\nn/a\tn/a\n14\t0.125\n15\t0.0625\n");
  EXPECT_EQ(test::Gunzip(beh + "_run-1_recording-rightforce_physio.tsv.gz"), "5\n6\n7\n");
  const auto physio = json::parse(test::ReadFile(beh + "_run-2_recording-leftforce_physio.json"));
  EXPECT_EQ(physio["SamplingFrequency"], 100.0);
  EXPECT_EQ(physio["StartTime"], 0.0);
  EXPECT_EQ(physio["Columns"], json::array({"fz_N", "vx_mps"}));
  EXPECT_EQ(physio["fz_N"]["Units"], "N");
  EXPECT_EQ(physio["vx_mps"]["Units"], "m/s");
  // The faulted trial (run 3) recorded samples but is not exported.
  EXPECT_FALSE(fs::exists(beh + "_run-3_recording-leftforce_physio.tsv.gz"));
  std::size_t physio_rows = 0;
  for (const auto& f : files)
    if (f.path.ends_with("_physio.tsv.gz")) physio_rows += f.rows;
  EXPECT_EQ(physio_rows, 4u + 3u + 6u);

  // The protocol as run, and its hash as the database recorded it.
  EXPECT_EQ(test::ReadFile(ds + "/code/protocol-TwoWords.toml"), "# p");
  const auto study = d.FindStudy("Two Words");
  ASSERT_TRUE(study);
  EXPECT_NE(test::ReadFile(ds + "/code/hashes.tsv")
                .find("code/protocol-TwoWords.toml\t" + study->protocol_hash),
            std::string::npos);
}

TEST(ExportBids, CodesThatShareALabelAreRefused) {
  test::TempDir dir;
  Database d(dir.File("b.db"));
  test_record::Fill(d);
  const auto other = d.CreateStudy({.name = "Other", .protocol_toml = "# q", .seed = 2});
  // sub-P01, as P-01; with a session (a code only reserved has no data and is not exported).
  d.StartSession({.participant_id = d.AddParticipant({.study_id = other, .code = "P01"})});
  try {
    ExportBids(d, dir.File("bids"));
    ADD_FAILURE() << "two participants were written as one";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("b.db"), std::string::npos) << what;
    EXPECT_NE(what.find("participant.code"), std::string::npos) << what;
    EXPECT_NE(what.find("sub-P01"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace hapticlab::db::export_bids_test
