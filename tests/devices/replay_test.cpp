// The replay test double (tests/util/include/hapticlab/test/replay_device.hpp): the latest sample
// at or before the clock, stamped with the clock on the replay's own time base, the link lost after
// the last sample, and commanded forces kept without growing the buffer (WriteForce runs on the
// real-time tick).

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "hapticlab/test/replay_device.hpp"

namespace hapticlab::devices::replay_test {
namespace {

using test::ReplayDevice;
using test::TrajectorySample;

// Three samples of a stroke along x recorded from t = 10 s (not 0: the replay's clock counts
// from the first sample).
std::vector<TrajectorySample> Stroke() {
  std::vector<TrajectorySample> s(3);
  for (int i = 0; i < 3; ++i) {
    s[i].t_s = 10.0 + 0.1 * i;
    s[i].p_m = {0.01 * i, 0, -0.001};
    s[i].v_mps = {0.1, 0, 0};
  }
  return s;
}

TEST(Replay, ReadsTheLatestSampleAtOrBeforeTheClockThenLosesTheLink) {
  double now_s = 0;
  ReplayDevice dev(Stroke(), [&] { return now_s; });
  EXPECT_EQ(dev.Capabilities().name, "replay");
  DeviceSample out;
  const auto read = [&](double t_s) {
    now_s = t_s;
    return dev.Read(&out);
  };
  ASSERT_EQ(read(0.0), ReadResult::kOk);
  EXPECT_DOUBLE_EQ(out.state.p_m.x(), 0.0);
  EXPECT_DOUBLE_EQ(out.t_s, 0.0);
  ASSERT_EQ(read(0.15), ReadResult::kOk);  // between samples 1 and 2: sample 1, not 2
  EXPECT_DOUBLE_EQ(out.state.p_m.x(), 0.01);
  EXPECT_DOUBLE_EQ(out.state.v_mps.x(), 0.1);
  EXPECT_NEAR(out.t_s, 0.15, 1e-12);      // (0.15 + 10) - 10 in doubles
  ASSERT_EQ(read(0.2), ReadResult::kOk);  // exactly on the last sample
  EXPECT_DOUBLE_EQ(out.state.p_m.x(), 0.02);
  EXPECT_FALSE(dev.finished());
  EXPECT_EQ(read(0.2001), ReadResult::kLost);
  EXPECT_TRUE(dev.finished());
  EXPECT_STREQ(ReadResultName(ReadResult::kLost), "lost");
}

TEST(Replay, ForcesAreKeptUpToTheReservedRoomWithoutReallocating) {
  ReplayDevice dev(Stroke(), [] { return 0.0; });
  const auto* data = dev.forces().data();
  const auto room = dev.forces().capacity();
  ASSERT_GE(room, 800u);  // a 4 kHz loop over the 0.2 s stroke
  for (std::size_t i = 0; i < room + 100; ++i) {
    dev.WriteForce(Eigen::Vector3d(0, 0, static_cast<double>(i)));
  }
  EXPECT_EQ(dev.forces().size(), room);
  EXPECT_EQ(dev.forces().data(), data);  // never reallocated
  EXPECT_DOUBLE_EQ(dev.forces().back().z(), static_cast<double>(room - 1));
}

TEST(Replay, RefusesAnEmptyOrUnorderedTrajectory) {
  const auto clock = [] { return 0.0; };
  EXPECT_THROW(ReplayDevice({}, clock), std::logic_error);
  auto s = Stroke();
  std::swap(s[0], s[2]);
  EXPECT_THROW(ReplayDevice(s, clock), std::logic_error);
}

}  // namespace
}  // namespace hapticlab::devices::replay_test
