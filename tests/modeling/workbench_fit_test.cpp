// Workbench fitting: parameters of a simulated truth recovered within their intervals, and the
// fit's report in the solver summary's terms (core/solver_summary.hpp).

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::workbench_fit_test {
namespace {

TEST(WorkbenchFit, RecoversCoulombViscousAndStiffnessWithConvergedSummaries) {
  TruthParams t;
  t.effects = {"coulomb", "viscous", "hc-exponent"};
  t.Set(key::kMuK, 0.35);
  t.Set(key::kMuB_Ns_per_m, 0.8);
  t.K1mm_N = 1.7;
  t.Set(key::kN, 1.4);
  t.duration_s = 12;
  t.seed = 7;
  // Exact kinematics: measured velocities with noise bias mu_k against mu_b (errors in the
  // regressors), which is the replay's property, not the fitter's.
  t.pos_noise_m = t.vel_noise_mps = 0;
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  Model m;
  AddEffects(&m, {"coulomb", "viscous", "hc-exponent"}, r);
  const double mu_start = m.At(key::kMuK);
  const auto rep = Fit(&m, r, {.vibration = false, .algorithm1_init = false});
  ASSERT_EQ(rep.channels.size(), 2u);
  EXPECT_TRUE(rep.IsUsable());
  for (const auto& c : rep.channels) {
    const SolverSummary& s = c.summary;  // a FitSummary is a SolverSummary
    EXPECT_TRUE(s.converged) << ChannelName(c.summary.channel) << ": " << s.message;
    EXPECT_GT(s.iterations, 0);
    EXPECT_LE(s.final_cost, s.initial_cost);
    EXPECT_EQ(c.summary.termination, FitTermination::kConverged);
    EXPECT_EQ(TerminationText(c.summary), "converged");
  }
  EXPECT_NE(mu_start, m.At(key::kMuK));
  EXPECT_NEAR(m.At(key::kMuK), 0.35, 0.01);
  EXPECT_NEAR(m.At(key::kMuB_Ns_per_m), 0.8, 0.1);
  EXPECT_NEAR(m.At(key::kK1mm_N), 1.7, 0.02);
  EXPECT_NEAR(m.At(key::kN), 1.4, 0.02);
  const ChannelFit* fr = rep.Find(Channel::kFriction);
  ASSERT_NE(fr, nullptr);
  EXPECT_EQ(fr->params.size(), 2u);
  EXPECT_EQ(rep.Find(Channel::kVibration), nullptr);
}

// The termination's words are the reports' (fit, diagnose, model fit-contact, JSON): every value
// has a name that parses back, and a fit not run says why in parentheses.
TEST(WorkbenchFit, EveryTerminationHasANameAndANotRunFitSaysWhy) {
  for (const auto t : {FitTermination::kConverged, FitTermination::kIterationLimit,
                       FitTermination::kFailed, FitTermination::kNotRun}) {
    EXPECT_FALSE(NameOf(kFitTerminationNames, t).empty());
    EXPECT_EQ(FromName(kFitTerminationNames, NameOf(kFitTerminationNames, t)), t);
  }
  for (const auto w : {FitNotRun::kNoFittedParameter, FitNotRun::kTooFewSamples,
                       FitNotRun::kNoAcceleration, FitNotRun::kTooFewVibrationWindows}) {
    EXPECT_FALSE(NameOf(kFitNotRunNames, w).empty());
    EXPECT_EQ(FromName(kFitNotRunNames, NameOf(kFitNotRunNames, w)), w);
  }
  FitSummary s;
  s.termination = FitTermination::kIterationLimit;
  EXPECT_EQ(TerminationText(s), "iteration limit");
  s.termination = FitTermination::kNotRun;
  s.not_run = FitNotRun::kTooFewVibrationWindows;
  EXPECT_EQ(TerminationText(s), "not run (too few vibration windows)");
}

TEST(WorkbenchFit, TooFewSamplesIsReportedNotThrown) {
  TruthParams t;
  t.effects = {"coulomb"};
  t.duration_s = 2;
  const auto sim = Simulate(t);
  auto r = PrepareReplay(sim.m);
  // Keep two samples in contact: fewer than three per fitted parameter (mu_k).
  int kept = 0;
  for (auto& s : r.mutable_samples())
    if (s.contact && ++kept > 2) s.contact = false;
  Model m;
  AddEffects(&m, {"coulomb"}, r);
  const auto rep = Fit(&m, r, {.vibration = false});
  const ChannelFit* fr = rep.Find(Channel::kFriction);
  ASSERT_NE(fr, nullptr);
  EXPECT_FALSE(fr->summary.converged);
  EXPECT_FALSE(fr->summary.usable);
  EXPECT_EQ(fr->summary.termination, FitTermination::kNotRun);
  EXPECT_EQ(fr->summary.not_run, FitNotRun::kTooFewSamples);
  EXPECT_EQ(TerminationText(fr->summary), "not run (too few samples)");
  EXPECT_FALSE(rep.IsUsable());
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_fit_test
