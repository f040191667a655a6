// One planned trial through the one trial path (runner/src/trial.cpp) on the simulated rig:
// the screen's wording of what lies where (and whether a real sample must be placed); both sides
// run and the simulated observer rates what the hand felt, one rating per criterion on the scale,
// the same again for the same seeds; a simulated training trial without screens is recorded without
// rendering; a link dropout faults the trial (re-queued, no ratings).

#include "../../runner/src/trial.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../../runner/src/participant.hpp"
#include "trial_fixture.hpp"

namespace hapticlab::runner::internal::trial_test {
namespace {

using test_trial::Session;

TEST(Trial, TheScreenSaysWhatLiesWhere) {
  Session s;
  const auto t = s.Trial(PhaseKind::kMain, "real:Cork", "virtual:Cork", "Hybrid");
  const auto screen = ScreenOf(s.protocol, t, ParseStimuli(t), 3, 12);
  EXPECT_EQ(screen.index, 3);
  EXPECT_EQ(screen.total, 12);
  EXPECT_EQ(screen.placement, "left = real Cork, right = virtual");
  EXPECT_TRUE(screen.real_sample) << "the experimenter places the real Cork first";
  EXPECT_EQ(screen.plan_number, t.plan_index + 1);
  EXPECT_EQ(screen.sides, 2);
  EXPECT_EQ(screen.method, "Hybrid");
  EXPECT_EQ(screen.criteria, s.protocol.criteria);
  EXPECT_EQ(screen.scale_max, s.protocol.scale_max);
  const auto training = s.Trial(PhaseKind::kTraining, "virtual:Denim", "", "FF", 1);
  const auto ts = ScreenOf(s.protocol, training, ParseStimuli(training), 1, 4);
  EXPECT_EQ(ts.placement, "left = virtual, right = nothing");
  EXPECT_FALSE(ts.real_sample) << "nothing real to place for a virtual training sample";
  EXPECT_EQ(ts.sides, 1);
}

struct Ran {
  Outcome outcome;
  std::vector<FeltTrial> felt;
  int sides = 0;
};

Ran Execute(Session& s, const db::Trial& t, std::uint64_t seed, double fault_rate = 0) {
  Ran r;
  RunOptions opt{.db_path = s.db_path, .participant = "P01", .record = RecordMode::kNone};
  opt.fault_rate = fault_rate;
  opt.on_felt = [&](const FeltTrial& f) { r.felt.push_back(f); };
  opt.on_side = [&](const SideReport&) { ++r.sides; };
  const auto participant = MakeParticipant(*s.rig, s.lab, opt, 11);
  const TrialContext c{*s.rig, *participant, opt, nullptr, s.database, s.session};
  const TrialStimuli stimuli = ParseStimuli(t);
  r.outcome = ExecuteTrial(s.lab, t, stimuli, seed, c, ScreenOf(s.protocol, t, stimuli, 1, 1));
  return r;
}

TEST(Trial, BothSidesRunAndTheObserverRatesWhatTheHandFelt) {
  Session s;
  const auto t = s.Trial(PhaseKind::kMain, "real:Cork", "virtual:Cork", "Hybrid");
  const auto r = Execute(s, t, 1234);
  ASSERT_FALSE(r.outcome.fault) << r.outcome.fault_detail;
  EXPECT_FALSE(r.outcome.aborted);
  EXPECT_EQ(r.sides, 2);
  EXPECT_DOUBLE_EQ(r.outcome.stimulus_s, 2 * s.protocol.stimulus_duration_s);
  ASSERT_EQ(r.outcome.ratings.size(), s.protocol.criteria.size());
  for (std::size_t i = 0; i < r.outcome.ratings.size(); ++i) {
    const auto& x = r.outcome.ratings[i];
    EXPECT_EQ(x.criterion, s.protocol.criteria[i]);
    EXPECT_GE(x.score, s.protocol.scale_min);
    EXPECT_LE(x.score, s.protocol.scale_max);
    EXPECT_GT(x.response_time_s, 0);
    EXPECT_EQ(x.source, db::kRaterSimulated);
  }
  ASSERT_EQ(r.felt.size(), 1u);
  EXPECT_EQ(r.felt[0].material, "Cork");
  EXPECT_EQ(r.felt[0].distances.size(), s.protocol.criteria.size());
  // The hand pressed on both sides (the real one through the ground truth).
  EXPECT_GT(r.felt[0].felt[0].mean_force_N, 0.1);
  EXPECT_GT(r.felt[0].felt[1].mean_force_N, 0.1);
  // The same participant seed, trial and attempt: the same strokes, felt and ratings.
  Session again;
  const auto r2 =
      Execute(again, again.Trial(PhaseKind::kMain, "real:Cork", "virtual:Cork", "Hybrid"), 1234);
  ASSERT_EQ(r2.outcome.ratings.size(), r.outcome.ratings.size());
  for (std::size_t i = 0; i < r.outcome.ratings.size(); ++i)
    EXPECT_EQ(r2.outcome.ratings[i].score, r.outcome.ratings[i].score) << i;
  EXPECT_EQ(r2.felt[0].felt[1].mean_force_N, r.felt[0].felt[1].mean_force_N);
}

TEST(Trial, ASimulatedTrainingTrialWithoutScreensIsNotRendered) {
  Session s;
  const auto r = Execute(s, s.Trial(PhaseKind::kTraining, "virtual:Denim", "", "FF"), 1);
  EXPECT_EQ(r.sides, 0);
  EXPECT_TRUE(r.outcome.ratings.empty());
  EXPECT_FALSE(r.outcome.fault);
}

TEST(Trial, ALinkDropoutFaultsTheTrialWithoutRatings) {
  Session s;
  const auto r = Execute(s, s.Trial(PhaseKind::kMain, "virtual:Cork", "real:Cork", "FF"), 7, 1.0);
  EXPECT_TRUE(r.outcome.fault);
  EXPECT_FALSE(r.outcome.untouched);
  EXPECT_NE(r.outcome.fault_detail.find("watchdog: left side"), std::string::npos)
      << r.outcome.fault_detail;
  EXPECT_NE(r.outcome.fault_detail.find("re-queued"), std::string::npos);
  EXPECT_TRUE(r.outcome.ratings.empty());
  EXPECT_TRUE(r.felt.empty());
}

}  // namespace
}  // namespace hapticlab::runner::internal::trial_test
