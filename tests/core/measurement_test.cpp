#include "hapticlab/core/measurement.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::measurement_test {
namespace {

TEST(Measurement, ReadsAndRoundTrips) {
  const std::string text =
      "# hapticlab-measurement v1\n# material: Cork\n# speed_mps: 0.04\n"
      "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N,acc_mps2\n"
      "0,0,0,-1e-4,0.04,0,0,-0.1,0,0.5,0.25\n"
      "0.001,4e-5,0,-1e-4,0.04,0,0,-0.1,0,0.5,-0.5\n";
  const auto m = ParseMeasurementCsv(text, "m.csv");
  EXPECT_EQ(m.material, "Cork");
  EXPECT_EQ(m.metadata.at("speed_mps"), "0.04");
  ASSERT_EQ(m.rows.size(), 2u);
  EXPECT_TRUE(m.has_acceleration);
  EXPECT_DOUBLE_EQ(m.rows[1].acc_mps2, -0.5);
  test::TempDir dir;
  WriteMeasurementCsv(dir.File("o.csv"), m);
  const auto back = ReadMeasurementCsv(dir.File("o.csv"));
  EXPECT_EQ(back.material, "Cork");
  EXPECT_EQ(back.rows[1].p_m, m.rows[1].p_m);
  EXPECT_EQ(back.rows[0].f_N, m.rows[0].f_N);
}

TEST(Measurement, ReadsLineByLineWithinItsBounds) {
  const std::string head =
      "\xEF\xBB\xBF# hapticlab-measurement v1\r\n# material: Cork\r\n"
      "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\r\n";
  // A byte-order mark, CRLF and a last line without a newline read as the plain file does.
  const auto m =
      ParseMeasurementCsv(head + "0,1,2,3,4,5,6,7,8,9\r\n\r\n0.5,1,2,3,4,5,6,7,8,-9", "b.csv");
  ASSERT_EQ(m.rows.size(), 2u);
  EXPECT_EQ(m.material, "Cork");
  EXPECT_EQ(m.row_lines, (std::vector<int>{4, 6}));
  EXPECT_DOUBLE_EQ(m.rows[1].f_N.z(), -9);
  test::TempDir dir;
  test::WriteFile(dir.File("b.csv"), head + "0,1,2,3,4,5,6,7,8,9\r\n\r\n0.5,1,2,3,4,5,6,7,8,-9");
  EXPECT_EQ(ReadMeasurementCsv(dir.File("b.csv")).rows[1].t_s, 0.5);
  // A NUL byte ends no number; a line longer than 1 MiB is refused, not read whole.
  EXPECT_THROW(
      ParseMeasurementCsv(head + "0,1,2,3,4,5,6,7,8,9" + std::string(1, '\0') + "1\n", "z.csv"),
      InputError);
  try {
    ParseMeasurementCsv(head + "0," + std::string(2 << 20, '1'), "l.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("l.csv:4: line longer than 1 MiB"), std::string::npos)
        << e.what();
  }
}

// Concatenated recordings carry a `recording` column: read, written back, and a bad id is
// refused naming its line and column.
TEST(Measurement, RecordingColumnKeepsConcatenatedRecordingsApart) {
  const std::string head =
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N,recording\n";
  const auto m = ParseMeasurementCsv(
      head + "0,0,0,0,0,0,0,0,0,1,0\n0.1,0,0,0,0,0,0,0,0,1,0\n0.2,0,0,0,0,0,0,0,0,1,3\n", "c.csv");
  EXPECT_EQ(m.recording_ids, (std::vector<int>{0, 0, 3}));
  test::TempDir dir;
  WriteMeasurementCsv(dir.File("c.csv"), m);
  EXPECT_EQ(ReadMeasurementCsv(dir.File("c.csv")).recording_ids, m.recording_ids);
  EXPECT_TRUE(
      ParseMeasurementCsv(head.substr(0, head.size() - 11) + "\n0,0,0,0,0,0,0,0,0,1\n", "n.csv")
          .recording_ids.empty());
  for (const char* bad : {"1.5", "-1"}) {
    try {
      ParseMeasurementCsv(head + "0,0,0,0,0,0,0,0,0,1," + bad + "\n", "b.csv");
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("b.csv:3: recording"), std::string::npos) << e.what();
    }
  }
}

TEST(Measurement, KinematicsOnlyDifferentiatesPositions) {
  const auto m = ParseMeasurementCsv(
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m\n0,0,0,0\n0.5,1,0,0\n1,3,0,0\n", "k.csv",
      {.kinematics_only = true});
  EXPECT_FALSE(m.has_forces);
  EXPECT_DOUBLE_EQ(m.rows[1].v_mps.x(), 3.0);
  EXPECT_DOUBLE_EQ(m.rows[0].v_mps.x(), 2.0);
}

TEST(Measurement, ErrorsNameFileLineAndColumn) {
  const std::string head =
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n";
  try {
    ParseMeasurementCsv(head + "0,0,0,0,0,0,0,0,0,0\n0,0,0,0,0,0,0,0,0,0\n", "t.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.csv:4: t_s: time must increase"), std::string::npos)
        << e.what();
  }
  try {
    ParseMeasurementCsv(head + "0,0,0,nan,0,0,0,0,0,0\n", "n.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("n.csv:3: z_m: value is not finite"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ParseMeasurementCsv("t_s,x_m\n0,0\n", "h.csv"), InputError);  // no v1 tag
  try {
    ParseMeasurementCsv(
        "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n0,0,0,0,0,0,0\n",
        "f.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fx_N: column is missing"), std::string::npos) << e.what();
  }
}

TEST(Measurement, VibrationOnlyFilesAreAKindWhenAskedFor) {
  const std::string text =
      "# hapticlab-measurement v1\n# speed_mps: 0.1\nt_s,acc_mps2\n0,0.5\n0.001,-0.25\n";
  const auto m = ParseMeasurementCsv(text, "v.csv", {.allow_vibration_only = true});
  EXPECT_FALSE(m.has_kinematics);
  EXPECT_FALSE(m.has_forces);
  EXPECT_TRUE(m.has_acceleration);
  ASSERT_EQ(m.rows.size(), 2u);
  EXPECT_EQ(m.rows[1].t_s, 0.001);
  EXPECT_EQ(m.rows[1].acc_mps2, -0.25);
  EXPECT_EQ(m.metadata.at("speed_mps"), "0.1");
  // Without the option, or with a bad cell, it is refused naming the file, line and column.
  try {
    ParseMeasurementCsv(text, "v.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x_m"), std::string::npos) << e.what();
  }
  try {
    ParseMeasurementCsv(text + "0.002,inf\n", "v.csv", {.allow_vibration_only = true});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("v.csv:6: acc_mps2"), std::string::npos) << e.what();
  }
  // A file with positions stays a kinematic measurement.
  EXPECT_THROW(ParseMeasurementCsv("# hapticlab-measurement v1\nt_s,x_m,acc_mps2\n0,0,0\n", "p.csv",
                                   {.allow_vibration_only = true}),
               InputError);
}

}  // namespace
}  // namespace hapticlab::measurement_test
