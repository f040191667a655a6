#include "hapticlab/runner/offline.hpp"

#include <gtest/gtest.h>

#include "../renderer/test_materials.hpp"

namespace hapticlab::runner::offline_test {
namespace {

TEST(Offline, SameTicksAsTheForceModelAndVibrationAtItsRate) {
  const auto m = test::TexturedMaterial();
  Measurement traj;
  for (int k = 0; k < 1000; ++k) {
    MeasurementRow r;
    r.t_s = 10.0 + k * 1e-3;  // absolute times need not start at 0
    r.p_m = {0.05 * k * 1e-3, 0.001, -0.1e-3};
    r.v_mps = {0.05, 0, 0};
    traj.rows.push_back(r);
  }
  renderer::RenderOptions o;
  o.algorithm = renderer::ForceAlgorithm::kFric2;
  o.hybrid_filter = false;
  const auto out = RenderOffline(m, o, traj);
  ASSERT_EQ(out.rows.size(), 1000u);
  renderer::ForceModel f(m, o.algorithm, 0.5 * o.device_max_stiffness_N_per_m);
  for (std::size_t k = 0; k < 1000; ++k) {
    renderer::ToolState s{traj.rows[k].p_m, traj.rows[k].v_mps};
    const auto expect = f.Step(s);
    ASSERT_NEAR((out.rows[k].force_N - expect.force_N).norm(), 0, 1e-12) << k;
    EXPECT_FALSE(out.rows[k].fault);
  }
  // 0.999 s at 10 kHz: one vibration sample per 0.1 ms, the first at t = 0.
  EXPECT_EQ(out.vibration_mps2.size(), 9991u);
  double e = 0;
  for (double a : out.vibration_mps2) e += a * a;
  EXPECT_GT(e, 0.0);
}

}  // namespace
}  // namespace hapticlab::runner::offline_test
