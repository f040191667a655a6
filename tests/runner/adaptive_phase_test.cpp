// Adaptive phases through the study runner with the simulated lab: every trial's stimulus
// value and answer recorded, the staircase's record follows its rules, resume continues
// exactly (an interrupted session records what an uninterrupted one does), QUEST+ finds the
// simulated observer's threshold. Every interval runs through the one trial path (the
// real-time engine on the simulated rig, the hand stroking it), on the generic simulated
// device and on the Falcon twin alike; a link dropout faults the trial through the watchdog.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/psychophysics/quest_plus.hpp"
#include "hapticlab/psychophysics/staircase.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::adaptive_phase_test {
namespace {

std::string Protocol(const std::string& phases) {
  return R"(
[study]
name = "jnd-test"
seed = 99
criteria = ["vibration"]
stimulus_duration_s = 0.05
profiles = ")" +
         std::string(HL_SOURCE_DIR) + R"(/studies/shin2019/profiles.toml"

[[material]]
id = "Denim"

[[method]]
name = "Hybrid"
algorithm = "fric2"
)" + phases;
}

const char* kStaircase = R"(
[[phase]]
kind = "staircase"
material = "Denim"
method = "Hybrid"
parameter = "vibration.gain"
task = "2afc"
reference = 1.0
step_type = "log"
steps = [0.2, 0.1]
start = [0.6, 0.05]
min = 0.005
max = 2.0
reversals = 8
discard_reversals = 2
max_trials = 25
[phase.simulated_observer]
threshold = 0.2
slope = 3.0
lapse = 0.02
)";

struct Record {
  int plan_index = 0, track = 0;
  double level = 0, correct = 0, response = 0, interval = 0;
  bool operator==(const Record&) const = default;
};

std::vector<Record> Records(const std::string& db_path) {
  db::Database d(db_path);
  std::vector<Record> out;
  for (const auto& st : d.Studies())
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id))
        for (const auto& t : d.Trials(se.id)) {
          EXPECT_EQ(t.status, db::TrialStatus::kCompleted) << t.plan_index;
          Record r{.plan_index = t.plan_index, .track = t.repetition};
          for (const auto& x : d.Ratings(t.id)) {
            if (x.criterion == "level") r.level = x.score;
            if (x.criterion == "correct") r.correct = x.score;
            if (x.criterion == "response") r.response = x.score;
            if (x.criterion == "interval") r.interval = x.score;
          }
          out.push_back(r);
        }
  return out;
}

TEST(AdaptivePhase, StaircaseRecordsEveryTrialByItsRules) {
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(kStaircase);
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("s.db"), .participant = "P01", .record = RecordMode::kForce};
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kCompleted);
  const auto rec = Records(o.db_path);
  ASSERT_EQ(static_cast<int>(rec.size()), s.completed);
  ASSERT_GE(rec.size(), 16u);  // two tracks of at least 8 trials (8 reversals) each
  std::vector<psychophysics::StaircaseTrial> h;
  for (const auto& r : rec) {
    // 2AFC: the answer is correct exactly when the chosen interval is the comparison's.
    EXPECT_EQ(r.correct == 1, r.response == r.interval);
    EXPECT_TRUE(r.interval == 1 || r.interval == 2);
    h.push_back({r.track, r.level, r.correct == 1});
  }
  // The recorded levels are the ones the rules give (Replay throws otherwise), and both
  // tracks stopped.
  const auto tracks = psychophysics::ReplayStaircase(p.phases[0].adaptive->staircase, h);
  for (const auto& t : tracks) EXPECT_TRUE(t.done);
  // The stimuli were rendered and recorded: one force stream per interval.
  db::Database d(o.db_path);
  const auto trials = d.Trials(s.session_id);
  const auto chunks = d.TrajectoryChunks(trials.front().id);
  std::set<std::string> streams;
  for (const auto& c : chunks) streams.insert(c.stream);
  EXPECT_EQ(streams, (std::set<std::string>{"i1_force", "i2_force"}));
}

TEST(AdaptivePhase, EveryIntervalRunsThroughTheEngineOnTheSimulatedRig) {
  // Each interval of each trial is one run of the real-time engine on the rig's virtual clock
  // for exactly the stimulus duration: the hand was stepped once per force tick, the Hybrid
  // method ran 10 vibration ticks per force tick, the stylus met the rendered surface, and
  // the force stream of each interval holds every tick.
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(kStaircase);
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  std::vector<SideReport> sides;
  RunOptions o{.db_path = dir.File("e.db"), .participant = "P01", .record = RecordMode::kForce};
  o.on_side = [&](const SideReport& r) { sides.push_back(r); };
  const auto s = RunStudy(p, o);
  ASSERT_EQ(s.status, db::SessionStatus::kCompleted);
  EXPECT_EQ(s.faults, 0);
  ASSERT_EQ(static_cast<int>(sides.size()), 2 * s.completed);
  const auto force_ticks = static_cast<std::uint64_t>(std::lround(p.stimulus_duration_s * 1000));
  for (std::size_t i = 0; i < sides.size(); ++i) {
    const auto& r = sides[i];
    EXPECT_EQ(r.side, static_cast<int>(i % 2)) << "interval index";
    EXPECT_EQ(r.stimulus, "virtual:Denim");
    EXPECT_EQ(r.engine.force_ticks, force_ticks);
    EXPECT_EQ(r.hand_ticks, force_ticks);
    EXPECT_EQ(r.engine.vibration_ticks, 10 * force_ticks);
    EXPECT_EQ(
        r.engine.disconnects + r.engine.nan_faults + r.engine.stale_faults + r.engine.miss_faults,
        0u);
    EXPECT_GE(static_cast<double>(r.contact_ticks), 0.05 * static_cast<double>(force_ticks))
        << "trial " << r.plan_index;
  }
  db::Database d(o.db_path);
  std::size_t samples = 0;
  for (const auto& t : d.Trials(s.session_id))
    for (const auto& c : d.TrajectoryChunks(t.id)) samples += c.sample_count();
  EXPECT_EQ(samples, sides.size() * force_ticks);
}

TEST(AdaptivePhase, TheFalconTwinRecordsWhatTheGenericSimulatedRigDoes) {
  // The simulated observer answers from its psychometric function, so the record (levels,
  // intervals, answers) does not depend on which simulated device rendered the intervals;
  // on the twin every interval went through the real Falcon back-end.
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(kStaircase);
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("sim.db"), .participant = "P01", .record = RecordMode::kNone};
  ASSERT_EQ(RunStudy(p, o).status, db::SessionStatus::kCompleted);
  auto sr = OpenRig({.device = "falcon-twin", .rig_file = DefaultRig("falcon")});
  std::uint64_t ticks = 0, contact = 0;
  RunOptions t = o;
  t.db_path = dir.File("twin.db");
  t.device = "falcon-twin";
  t.rig = sr.get();
  t.on_side = [&](const SideReport& r) {
    ticks += r.engine.force_ticks;
    contact += r.contact_ticks;
  };
  const auto s = RunStudy(p, t);
  ASSERT_EQ(s.status, db::SessionStatus::kCompleted);
  EXPECT_EQ(s.faults, 0);
  EXPECT_GT(ticks, 0u);
  EXPECT_GE(dynamic_cast<devices::falcon::FalconDevice&>(*sr->device).packets(), ticks)
      << "one status packet per tick";
  EXPECT_GT(contact, ticks / 2);
  EXPECT_EQ(Records(t.db_path), Records(o.db_path));
}

TEST(AdaptivePhase, ALinkDropoutFaultsTheTrialThroughTheWatchdogAndItRunsAgain) {
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(kStaircase);
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("f.db"),
               .participant = "P01",
               .record = RecordMode::kNone,
               .fault_rate = 0.3};
  const auto s = RunStudy(p, o);
  ASSERT_EQ(s.status, db::SessionStatus::kCompleted);
  EXPECT_GT(s.faults, 0);
  db::Database d(o.db_path);
  int watchdog_events = 0, trial_faults = 0;
  for (const auto& e : d.Events(s.session_id)) {
    if (e.kind != db::EventKind::kDeviceFault) continue;
    watchdog_events += e.detail.rfind("disconnect at ", 0) == 0 &&
                       e.detail.find("(interval 1, tick") != std::string::npos;
    trial_faults += e.detail.rfind("watchdog: interval 1: ", 0) == 0;
  }
  EXPECT_EQ(trial_faults, s.faults);
  EXPECT_GE(watchdog_events, s.faults);
  // Every faulted trial ran again (none is left unfinished) and the record follows the rules.
  std::vector<psychophysics::StaircaseTrial> h;
  int repeated = 0;
  for (const auto& t : d.Trials(s.session_id)) {
    EXPECT_EQ(t.status, db::TrialStatus::kCompleted);
    repeated += t.attempts > 1;
  }
  EXPECT_GT(repeated, 0);
  for (const auto& r : Records(o.db_path)) h.push_back({r.track, r.level, r.correct == 1});
  for (const auto& t : psychophysics::ReplayStaircase(p.phases[0].adaptive->staircase, h))
    EXPECT_TRUE(t.done);
}

TEST(AdaptivePhase, ResumeContinuesExactly) {
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(kStaircase);
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("whole.db"), .participant = "P01", .record = RecordMode::kNone};
  RunStudy(p, o);
  const auto whole = Records(o.db_path);
  // The same participant stopped after 7 trials, then after 5 more each time, resumed to the end.
  RunOptions r = o;
  r.db_path = dir.File("pieces.db");
  r.stop_after_trials = 7;
  auto s = RunStudy(p, r);
  int resumes = 0;
  while (s.status != db::SessionStatus::kCompleted) {
    ASSERT_EQ(s.status, db::SessionStatus::kAborted);
    r.stop_after_trials = 5;
    s = ResumeStudy(r);
    ++resumes;
  }
  EXPECT_GE(resumes, 3);
  EXPECT_EQ(Records(r.db_path), whole);
}

TEST(AdaptivePhase, HardwareAndMissingObserverAreRefusedUpFront) {
  test::TempDir dir;
  std::string text = Protocol(kStaircase);
  text = text.substr(0, text.find("[phase.simulated_observer]"));
  std::ofstream(dir.File("p.toml")) << text;
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("s.db"), .participant = "P01"};
  try {
    RunStudy(p, o);
    ADD_FAILURE() << "ran without a simulated observer";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("phase[0].simulated_observer: missing"), std::string::npos)
        << e.what();
  }
  // A hardware device: refused before anything is recorded (the simulated rigs, sim and
  // falcon-twin, run adaptive phases).
  std::ofstream(dir.File("q.toml")) << Protocol(kStaircase);
  o.device = "falcon";
  try {
    RunStudy(protocols::LoadProtocol(dir.File("q.toml")), o);
    ADD_FAILURE() << "ran an adaptive phase on hardware";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "phase[0].kind: adaptive phases run on a simulated device (sim or falcon-twin)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(o.db_path));
}

// A participant at the window: the engine's stylus frames of each interval are shown, the answer
// comes from SessionUi::Choose. This one always picks the first interval, so a trial is
// correct exactly when the comparison was first.
class FirstIntervalUi : public SessionUi {
 public:
  bool Stimulus(const TrialScreen& t, int, const Eigen::Vector3d&, double) override {
    intervals_seen.insert(t.phase);
    return true;
  }
  std::optional<std::vector<double>> Rate(const TrialScreen&) override { return std::nullopt; }
  bool Break(double) override { return true; }
  std::optional<int> Choose(const TrialScreen& t) override {
    EXPECT_EQ(t.answers, (std::vector<std::string>{"1", "2"}));
    EXPECT_EQ(t.question, "Which interval was stronger?");
    ++asked;
    return asked > 12 ? std::nullopt : std::optional<int>(0);  // the experimenter aborts at 13
  }
  int asked = 0;
  std::set<std::string> intervals_seen;
};

TEST(AdaptivePhase, TheParticipantAnswersAtTheWindow) {
  test::TempDir dir;
  std::string text = Protocol(kStaircase);
  text = text.substr(0, text.find("[phase.simulated_observer]"));  // not needed with a UI
  text += "\n[consent]\ndocument = \"jnd consent form\"\nversion = \"1\"\n";
  std::ofstream(dir.File("p.toml")) << text;
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  FirstIntervalUi ui;
  RunOptions o{.db_path = dir.File("s.db"),
               .participant = "P01",
               .record = RecordMode::kNone,
               .ui = &ui,
               .ui_playback_speed = 1e6,
               .consent_confirmed_by = "E01"};  // a person answers
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kAborted);
  EXPECT_EQ(ui.intervals_seen,
            (std::set<std::string>{"staircase: interval 1 of 2", "staircase: interval 2 of 2"}));
  db::Database d(o.db_path);
  int completed = 0;
  for (const auto& t : d.Trials(s.session_id)) {
    if (t.status != db::TrialStatus::kCompleted) continue;
    ++completed;
    double response = 0, interval = 0, correct = 0;
    for (const auto& r : d.Ratings(t.id)) {
      if (r.criterion == "response") response = r.score;
      if (r.criterion == "interval") interval = r.score;
      if (r.criterion == "correct") correct = r.score;
    }
    EXPECT_EQ(response, 1);
    EXPECT_EQ(correct == 1, interval == 1);
  }
  EXPECT_EQ(completed, 12);
}

TEST(AdaptivePhase, QuestPlusFindsTheSimulatedObserversThreshold) {
  test::TempDir dir;
  std::ofstream(dir.File("p.toml")) << Protocol(R"(
[[phase]]
kind = "quest-plus"
material = "Denim"
method = "Hybrid"
parameter = "friction.mu_k"
task = "3afc"
reference = 0.3
fit = "weibull"
stimuli = { from = 0.005, to = 0.3, count = 24, spacing = "log" }
thresholds = { from = 0.01, to = 0.3, count = 25, spacing = "log" }
slopes = [1.5, 2.5, 4]
lapses = [0, 0.03]
trials = 80
[phase.simulated_observer]
threshold = 0.06
slope = 2.5
lapse = 0.0
)");
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  RunOptions o{.db_path = dir.File("q.db"), .participant = "P01", .record = RecordMode::kNone};
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kCompleted);
  const auto rec = Records(o.db_path);
  ASSERT_EQ(rec.size(), 80u);
  std::vector<std::pair<double, bool>> h;
  for (const auto& r : rec) h.emplace_back(r.level, r.correct == 1);
  const auto q = psychophysics::QuestPlus::Replay(p.phases[0].adaptive->quest, h);
  // The posterior's threshold marginal: the truth lies in its central 99 %.
  const auto m = q.ThresholdMarginal();
  const auto& th = p.phases[0].adaptive->quest.thresholds;
  double below = 0, at_or_below = 0;
  for (std::size_t i = 0; i < th.size(); ++i) {
    if (th[i] < 0.06 * (1 - 1e-9)) below += m[i];
    if (th[i] <= 0.06 * (1 + 0.08))
      at_or_below += m[i];  // the grid point nearest 0.06 (spacing 15 %)
  }
  EXPECT_LT(below, 0.995) << "posterior mean " << q.Mean().threshold;
  EXPECT_GT(at_or_below, 0.005) << "posterior mean " << q.Mean().threshold;
}

}  // namespace
}  // namespace hapticlab::runner::adaptive_phase_test
