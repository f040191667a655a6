// Workbench prediction against the channel formulas written out by hand (workbench_model.hpp):
// f_n = (d / 1 mm)^n (K + B d_dot), and without a Dahl bristle the friction is
// -(f_C tanh(v / 0.5 mm/s) v / |v| + mu_b v) with f_C = f_load (mu_k + dmu_s exp(-(v / v_s)^2)).

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::workbench_predict_test {
namespace {

Replay::Sample Touching(double d_m, double ddot_mps, double vx_mps, double vy_mps, double load_N,
                        int block) {
  Replay::Sample s{};
  s.d_m = d_m;
  s.ddot_mps = ddot_mps;
  s.vx_mps = vx_mps;
  s.vy_mps = vy_mps;
  s.speed_mps = std::hypot(vx_mps, vy_mps);
  s.fn_N = s.fload_N = load_N;
  s.contact = true;
  s.block = block;
  return s;
}

Model HandModel() {
  Model m;
  m.effects = {"coulomb", "viscous", "stribeck", "hc-damping", "hc-exponent"};
  m.Set(key::kK1mm_N, 2.0);
  m.Set(key::kN, 1.5);
  m.Set(key::kB1mm_Ns_per_m, 10.0);
  m.Set(key::kMuK, 0.4);
  m.Set(key::kMuB_Ns_per_m, 0.5);
  m.Set(key::kStribeckDmu, 0.2);
  m.Set(key::kStribeckSpeed_mps, 0.01);
  return m;
}

TEST(WorkbenchPredict, ForcesFollowTheChannelFormulas) {
  Replay r;
  r.mutable_samples().push_back(Touching(0.5e-3, 0.01, 0.02, 0, 1.2, 0));
  r.mutable_samples().push_back(Touching(1.2e-3, -0.02, 0.006, -0.008, 2.0, 1));
  Replay::Sample air{};
  r.mutable_samples().push_back(air);
  const auto p = Predict(HandModel(), r);
  ASSERT_EQ(p.fn_N.size(), 3u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& s = r.samples()[i];
    const double fn = std::pow(s.d_m / 1e-3, 1.5) * (2.0 + 10.0 * s.ddot_mps);
    EXPECT_NEAR(p.fn_N[i], fn, 1e-12) << i;
    const double v = s.speed_mps, mu = 0.4 + 0.2 * std::exp(-std::pow(v / 0.01, 2));
    const double g = s.fload_N * mu * std::tanh(v / 0.5e-3) / v;
    EXPECT_NEAR(p.ftx_N[i], -(g * s.vx_mps + 0.5 * s.vx_mps), 1e-12) << i;
    EXPECT_NEAR(p.fty_N[i], -(g * s.vy_mps + 0.5 * s.vy_mps), 1e-12) << i;
  }
  EXPECT_EQ(p.fn_N[2], 0.0);
  EXPECT_EQ(p.ftx_N[2], 0.0);
  EXPECT_EQ(p.fty_N[2], 0.0);
}

// Channels are typed inside the workbench and named only where printed: every channel has a
// name that parses back, and a map keyed by Channel (Errors::Normalized, the noise floors)
// iterates in name order, the order the reports have always listed the channels in.
TEST(WorkbenchPredict, EveryChannelHasANameAndChannelOrderIsNameOrder) {
  std::vector<std::string> names;
  for (const auto& [c, name] :
       std::map<Channel, std::string>{{Channel::kNormal, ChannelName(Channel::kNormal)},
                                      {Channel::kFriction, ChannelName(Channel::kFriction)},
                                      {Channel::kVibration, ChannelName(Channel::kVibration)}}) {
    EXPECT_EQ(FromName(kChannelNames, name), c) << name;
    names.push_back(name);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"friction", "normal_force", "vibration"}));
}

TEST(WorkbenchPredict, ErrorsAreNormalisedPerChannelAndSplitByBlock) {
  Replay r;
  r.mutable_samples().push_back(Touching(1e-3, 0, 0.02, 0, 1.0, 0));  // train
  r.mutable_samples().push_back(Touching(1e-3, 0, 0.02, 0, 2.0, 1));  // held out
  r.mutable_samples()[0].ftx_N = -0.5;
  r.mutable_samples()[1].ftx_N = -1.0;
  Prediction p;
  p.fn_N = {0.9, 2.4};
  p.ftx_N = {-0.5, -0.7};
  p.fty_N = {0, 0};
  const auto all = ComputeErrors(r, p, Split::kAll);
  // normal: sqrt((0.1^2 + 0.4^2) / (1^2 + 2^2)); friction: sqrt(0.3^2 / (0.5^2 + 1^2)).
  ASSERT_TRUE(all.normal_force.present && all.friction.present);
  EXPECT_FALSE(all.vibration.present);
  EXPECT_NEAR(all.normal_force.normalized, std::sqrt(0.17 / 5.0), 1e-12);
  EXPECT_NEAR(all.friction.normalized, std::sqrt(0.09 / 1.25), 1e-12);
  EXPECT_EQ(all.Normalized().size(), 2U);
  EXPECT_NEAR(all.Normalized().at(Channel::kFriction), all.friction.normalized, 0);
  EXPECT_NEAR(all.overall, (std::sqrt(0.17 / 5.0) + std::sqrt(0.09 / 1.25)) / 2, 1e-12);
  EXPECT_NEAR(all.normal_force_rms_N, std::sqrt(0.17 / 2), 1e-12);
  const auto train = ComputeErrors(r, p, Split::kTrain);
  EXPECT_NEAR(train.normal_force.normalized, 0.1, 1e-12);
  EXPECT_NEAR(train.friction.normalized, 0.0, 1e-12);
  const auto held = ComputeErrors(r, p, Split::kHeldOut);
  EXPECT_NEAR(held.normal_force.normalized, 0.2, 1e-12);
  // Residuals: measured minus predicted, friction along the motion (+x here).
  const auto res = ComputeResiduals(Model{}, r, p);
  EXPECT_NEAR(res.normal_N[1], -0.4, 1e-12);
  EXPECT_NEAR(res.friction_N[1], 1.0 - 0.7, 1e-12);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_predict_test
