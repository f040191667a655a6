// One stimulus side through the one trial path (runner/src/stimulus_side.cpp) on the
// simulated rig: a method's render options; a real side only measures (the commanded force
// is clamped to 1 nN while the hand strokes the ground truth) and a virtual side pushes; the
// recorded streams and the stored timing rows follow the side; a link dropout faults the side
// through the watchdog and is logged as a device-fault event naming the side.

#include "../../runner/src/stimulus_side.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/force_record.hpp"
#include "hapticlab/db/timing.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "trial_fixture.hpp"

namespace hapticlab::runner::internal::stimulus_side_test {
namespace {

using test_trial::Session;

TEST(StimulusSide, MethodOptionsAreTheMethodsAtTheStudyRates) {
  const protocols::Method m{
      .name = "X", .algorithm = "fric1", .vibration = false, .hybrid_filter = true};
  const auto o = MethodOptions(m, 77);
  EXPECT_EQ(o.algorithm, renderer::ForceAlgorithm::kFric1);
  EXPECT_FALSE(o.vibration);
  EXPECT_TRUE(o.hybrid_filter);
  EXPECT_EQ(o.force_rate_hz, 1000);
  EXPECT_EQ(o.vibration_rate_hz, 10000);
  EXPECT_EQ(o.seed, 77u);
}

// Runs `side` for 0.5 s (the small protocol's stimulus) recording every stream, the simulated
// participant's hand exploring it (with a link dropout 30 % into the side when `dropout`).
SideOutcome RunSide(Session& s, StimulusSide side, const db::Trial& t, bool dropout = false) {
  db::TrajectoryWriter writer(s.db_path);
  RunOptions opt{.db_path = s.db_path, .participant = "P01"};
  const auto participant = MakeParticipant(*s.rig, s.lab, opt, 5);
  Rng rng(5);
  participant->DrawExploration(rng, 1, nullptr);
  participant->DrawDropout(rng, dropout ? 1.0 : 0.0, 0.5);
  const TrialContext c{*s.rig, *participant, opt, &writer, s.database, s.session};
  const auto out = RunStimulusSide(side, c, rng, 0.5, t, TrialScreen{}, side.sample);
  writer.Flush();
  return out;
}

StimulusSide Side(Session& s, bool real, const std::string& stream) {
  StimulusSide side;
  side.model = &s.lab.models.at("Denim");
  side.real = real;
  side.material = "Denim";
  if (!real) side.options = MethodOptions(*s.protocol.FindMethod("Hybrid"), 3);
  side.sample = real ? 0 : 1;
  side.stream = stream;
  side.label = stream + " side";
  side.stimulus = (real ? "real:" : "virtual:") + std::string("Denim");
  return side;
}

// The largest commanded force magnitude in a recorded force stream [N].
double MaxCommand(const db::Database& d, std::int64_t trial, const std::string& stream) {
  const auto names = db::ForceChannelNames();
  const auto at = [&](const char* n) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
  };
  const std::size_t cx = at("cmd_fx_N"), cz = at("cmd_fz_N");
  double most = -1;
  for (const auto& c : d.TrajectoryChunks(trial)) {
    if (c.stream != stream) continue;
    const std::size_t nc = c.channels.size();
    for (std::size_t i = 0; i < c.sample_count(); ++i) {
      double f2 = 0;
      for (std::size_t k = cx; k <= cz; ++k) f2 += std::pow(c.samples[i * nc + k], 2);
      most = std::max(most, std::sqrt(f2));
    }
  }
  return most;
}

TEST(StimulusSide, ARealSideOnlyMeasuresAndAVirtualSidePushes) {
  Session s;
  const auto t = s.Trial(PhaseKind::kMain, "real:Denim", "virtual:Denim", "Hybrid");
  const auto real = RunSide(s, Side(s, true, "left"), t);
  const auto virt = RunSide(s, Side(s, false, "right"), t);
  EXPECT_FALSE(real.fault) << real.detail;
  EXPECT_FALSE(virt.fault) << virt.detail;
  EXPECT_FALSE(real.untouched) << real.detail;
  EXPECT_FALSE(virt.untouched) << virt.detail;
  EXPECT_NEAR(static_cast<double>(real.stats.force_ticks), 500, 1);
  // Both sides were felt by the hand (the real one through the ground truth).
  EXPECT_GT(real.felt.mean_force_N, 0.1);
  EXPECT_GT(virt.felt.mean_force_N, 0.1);
  const double real_cmd = MaxCommand(s.database, t.id, "left_force");
  const double virt_cmd = MaxCommand(s.database, t.id, "right_force");
  ASSERT_GE(real_cmd, 0) << "no left_force stream recorded";
  EXPECT_LE(real_cmd, 1.001e-9);  // clamped to 1 nN (the recorded float32 of 1e-9 N)
  EXPECT_GT(virt_cmd, 0.1);
  // The vibration stream only where the side vibrates (the virtual Hybrid side).
  std::map<std::string, std::size_t> samples;
  for (const auto& c : s.database.TrajectoryChunks(t.id)) samples[c.stream] += c.sample_count();
  EXPECT_FALSE(samples.contains("left_vibration"));
  EXPECT_NEAR(static_cast<double>(samples["right_vibration"]), 5000, 10);
  EXPECT_NEAR(static_cast<double>(samples["right_force"]), 500, 1);
  // Timing rows per side and loop, on the virtual clock.
  std::map<std::string, db::SideTiming> rows;
  for (const auto& r : db::StudySideTimings(s.database, s.database.Studies().at(0).id))
    rows[r.side + "/" + r.loop] = r;
  ASSERT_TRUE(rows.contains("left/force"));
  EXPECT_FALSE(rows.contains("left/vibration"));
  ASSERT_TRUE(rows.contains("right/vibration"));
  EXPECT_EQ(rows["right/force"].clock, "virtual");
  EXPECT_EQ(rows["right/force"].ticks, static_cast<std::int64_t>(virt.stats.force_ticks));
  EXPECT_EQ(rows["right/vibration"].rate_hz, 10000);
  EXPECT_EQ(rows["left/force"].attempt, 1);
}

TEST(StimulusSide, ALinkDropoutFaultsTheSideAndIsLogged) {
  Session s;
  const auto t = s.Trial(PhaseKind::kMain, "virtual:Denim", "real:Denim", "Hybrid");
  const auto out = RunSide(s, Side(s, false, "left"), t, true);
  EXPECT_TRUE(out.fault);
  EXPECT_EQ(out.detail.rfind("left side: ", 0), 0u) << out.detail;
  EXPECT_GT(out.stats.disconnects + out.stats.stale_faults, 0u) << out.detail;
  int logged = 0;
  for (const auto& e : s.database.Events(s.session))
    if (e.kind == db::EventKind::kDeviceFault && e.trial_id == t.id &&
        e.detail.find("left side") != std::string::npos)
      ++logged;
  EXPECT_GT(logged, 0);
}

}  // namespace
}  // namespace hapticlab::runner::internal::stimulus_side_test
