// Reading vibration recordings: steady parts of a free scan, and bad files named with their
// line and field.

#include "hapticlab/modeling/vibration_recording.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::vibration_recording_test {
namespace {

TEST(Vibration, RecordingsWithoutMetadataAreCutIntoSteadyParts) {
  // 3 s at 5 cm/s and 1 N, then 2 s at 10 cm/s and 1.5 N, sampled at 2 kHz.
  test::TempDir dir;
  Rng rng(4);
  std::ofstream o(dir.File("scan.csv"));
  o << "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N,acc_mps2\n";
  for (int i = 0; i < 10000; ++i) {
    const bool first = i < 6000;
    const double v = first ? 0.05 : 0.10, f = first ? 1.0 : 1.5;
    o << fmt::format("{},0,0,0,{},0,0,0,0,{},{}\n", i / 2000.0, v * (1 + 0.02 * rng.Normal()),
                     f * (1 + 0.02 * rng.Normal()), rng.Normal());
  }
  o.close();
  const auto segs = LoadRecordingSegments(dir.File("scan.csv"));
  ASSERT_EQ(segs.size(), 2u);
  EXPECT_NEAR(segs[0].speed_mps, 0.05, 0.002);
  EXPECT_NEAR(segs[0].force_N, 1.0, 0.01);
  EXPECT_NEAR(static_cast<double>(segs[0].acc.size()) / 2000.0, 3.0, 0.01);
  EXPECT_NEAR(segs[1].speed_mps, 0.10, 0.004);
  EXPECT_NEAR(segs[1].force_N, 1.5, 0.015);
}

TEST(Vibration, RecordingErrorsNameTheFile) {
  test::TempDir dir;
  std::vector<double> acc(1000);
  Rng rng(1);
  for (auto& a : acc) a = rng.Normal();
  // A gap in time.
  {
    std::ofstream o(dir.File("gap.csv"));
    o << "# hapticlab-measurement v1\n# speed_mps: 0.1\n# force_N: 1\nt_s,x_m,y_m,z_m,acc_mps2\n";
    for (int i = 0; i < 600; ++i)
      o << (i < 300 ? i : i + 5) / 1000.0 << ",0,0,0," << acc[static_cast<std::size_t>(i)] << "\n";
  }
  try {
    LoadRecording(dir.File("gap.csv"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gap.csv:305: t_s: gap"), std::string::npos) << e.what();
  }
  // Clipping.
  std::vector<double> clipped(acc);
  for (std::size_t i = 0; i < clipped.size(); ++i) clipped[i] = std::clamp(clipped[i], -1.0, 1.0);
  {
    std::ofstream o(dir.File("clip.csv"));
    o << "# hapticlab-measurement v1\n# speed_mps: 0.1\n# force_N: 1\nt_s,x_m,y_m,z_m,acc_mps2\n";
    for (std::size_t i = 0; i < clipped.size(); ++i)
      o << static_cast<double>(i) / 1000.0 << ",0,0,0," << clipped[i] << "\n";
  }
  EXPECT_THROW(LoadRecording(dir.File("clip.csv")), InputError);
  // No acceleration column.
  test::WriteFile(dir.File("noacc.csv"), "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m\n0,0,0,0\n");
  EXPECT_THROW(LoadRecording(dir.File("noacc.csv")), InputError);
  // Errors of every file at once.
  try {
    LoadRecordings(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_GE(e.diagnostics().size(), 3u) << e.what();
  }
}

TEST(Vibration, ARecordingsFolderThatIsMissingOrEmptyIsNamed) {
  test::TempDir dir;
  for (const auto& folder : {dir.File("missing"), dir.path()}) {
    try {
      LoadRecordings(folder);
      FAIL() << folder;
    } catch (const InputError& e) {
      ASSERT_EQ(e.diagnostics().size(), 1u);
      EXPECT_EQ(e.diagnostics()[0].file, folder);
      EXPECT_EQ(e.diagnostics()[0].field, "recordings");  // the library's name, not a flag
    }
  }
}

}  // namespace
}  // namespace hapticlab::modeling::vibration_recording_test
