// Adaptive phases (staircase, quest-plus) in protocols: parsing, defaults, and every
// problem reported with file, line and key.
#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::protocols::adaptive_test {
namespace {

const char* kBase = R"(
[study]
name = "jnd"
seed = 7
criteria = ["vibration"]
profiles = "profiles.toml"

[[material]]
id = "Denim"

[[method]]
name = "Hybrid"
algorithm = "fric2"

[[phase]]
kind = "training"
duration_s = 5
)";

const char* kStair = R"(
[[phase]]
kind = "staircase"
material = "Denim"
method = "Hybrid"
parameter = "vibration.gain"
task = "2afc"
reference = 1.0
step_type = "log"
steps = [0.2, 0.1]
start = [0.5, 0.05]
min = 0.01
max = 2.0
reversals = 10
discard_reversals = 2
max_trials = 50
[phase.simulated_observer]
threshold = 0.2
slope = 3.0
)";

const char* kQuest = R"(
[[phase]]
kind = "quest-plus"
material = "Denim"
method = "Hybrid"
parameter = "friction.mu_k"
task = "3afc"
reference = 0.3
fit = "logistic"
fit_lapse = 0.02
stimuli = { from = 0.0, to = 0.3, count = 16 }
thresholds = { from = 0.01, to = 0.3, count = 30, spacing = "log" }
slopes = [10, 20, 40]
trials = 40
)";

TEST(AdaptiveProtocol, ParsesStaircaseAndQuestPlusPhases) {
  const auto p = ParseProtocol(std::string(kBase) + kStair + kQuest, "jnd.toml");
  ASSERT_EQ(p.phases.size(), 3u);
  ASSERT_TRUE(p.phases[1].adaptive);
  const auto& s = *p.phases[1].adaptive;
  EXPECT_EQ(p.phases[1].kind, PhaseKind::kStaircase);
  EXPECT_EQ(s.parameter, "vibration.gain");
  EXPECT_EQ(s.staircase.start_levels, (std::vector<double>{0.5, 0.05}));
  EXPECT_EQ(s.staircase.step_type, psychophysics::StepType::kLog);
  EXPECT_EQ(s.staircase.up, 1);  // defaults: 1-up-2-down
  EXPECT_EQ(s.staircase.down, 2);
  EXPECT_DOUBLE_EQ(s.jnd_performance, 0.75);  // midway between 1/2 and 1
  EXPECT_TRUE(s.fit_lapse_free);
  ASSERT_TRUE(s.simulated_observer);
  EXPECT_EQ(s.simulated_observer->shape, psychophysics::Shape::kWeibull);  // the fit's by default
  const auto& q = *p.phases[2].adaptive;
  EXPECT_EQ(p.phases[2].kind, PhaseKind::kQuestPlus);
  EXPECT_EQ(q.quest.stimuli.size(), 16u);
  EXPECT_NEAR(q.quest.guess, 1.0 / 3, 1e-15);
  EXPECT_NEAR(q.quest.thresholds.back(), 0.3, 1e-12);
  EXPECT_FALSE(q.fit_lapse_free);
  EXPECT_EQ(q.quest_trials, 40);
  // Adaptive trials are chosen at run time: the plan holds only the training.
  const auto plan = Plan(p, 0);
  for (const auto& t : plan) EXPECT_EQ(t.phase, PhaseKind::kTraining);
}

TEST(AdaptiveProtocol, TheExampleStudyParses) {
  const auto p =
      LoadProtocol(std::string(HL_SOURCE_DIR) + "/studies/examples/vibration-gain-jnd.toml");
  ASSERT_TRUE(p.phases.back().adaptive);
  EXPECT_EQ(p.phases.back().adaptive->parameter, "vibration.gain");
}

TEST(AdaptiveProtocol, EveryProblemNamesFileLineAndKey) {
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"parameter = \"vibration.gain\"", "parameter = \"vibration.gian\"",
       ":23: phase[1].parameter: unknown parameter 'vibration.gian'"},
      {"material = \"Denim\"\nmethod", "material = \"Cotton\"\nmethod",
       ":21: phase[1].material: no [[material]] with id 'Cotton'"},
      {"method = \"Hybrid\"\nparameter = \"vib", "method = \"LPC\"\nparameter = \"vib",
       ":22: phase[1].method: no [[method]] named 'LPC'"},
      {"task = \"2afc\"", "task = \"4afc\"",
       ":24: phase[1].task: expected 2afc, 3afc or yes-no, got '4afc'"},
      {"reference = 1.0\n", "", ":19: phase[1].reference: missing"},
      {"steps = [0.2, 0.1]", "steps = [0.2, -0.1]", ":27: phase[1].steps: steps must be > 0"},
      {"start = [0.5, 0.05]", "start = [0.5, 3.0]",
       ":28: phase[1].start: start levels must lie within [min, max]"},
      {"min = 0.01", "min = 0.0", "phase[1].min: logarithmic steps need min > 0"},
      {"discard_reversals = 2", "discard_reversals = 10",
       ":32: phase[1].discard_reversals: expected fewer than reversals"},
      {"max_trials = 50", "max_trials = 0",
       ":33: phase[1].max_trials: expected an integer 1..10000"},
      {"max_trials = 50", "max_trials = 50\nrepetitions = 2",
       ":34: phase[1].repetitions: unknown key (a typo?)"},
      {"slope = 3.0", "slope = -3.0",
       "phase[1].simulated_observer.slope: expected a number > 0, got -3"},
      {"slope = 3.0", "slope = 3.0\nthreshhold = 1",
       "phase[1].simulated_observer.threshhold: unknown key"},
      {"task = \"2afc\"", "task = \"2afc\"\nfalse_alarm = 0.1",
       "phase[1].false_alarm: only a yes-no task"},
      {"task = \"2afc\"", "task = \"2afc\"\nfit = \"gumbel\"",
       "phase[1].fit: expected logistic, weibull or normal"},
      {"task = \"2afc\"", "task = \"2afc\"\nfit_lapse = \"maybe\"",
       "phase[1].fit_lapse: expected \"free\""},
      {"task = \"2afc\"", "task = \"2afc\"\njnd_performance = 0.4",
       "phase[1].jnd_performance: expected guess rate (0.5) < p < 1"},
  };
  for (const auto& c : cases) {
    std::string text = std::string(kBase) + kStair;
    const auto pos = text.find(c.from);
    ASSERT_NE(pos, std::string::npos) << c.from;
    text.replace(pos, c.from.size(), c.to);
    try {
      ParseProtocol(text, "bad.toml");
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("bad.toml" + (c.expect[0] == ':' ? c.expect : ":")), std::string::npos)
          << msg;
      EXPECT_NE(msg.find(c.expect), std::string::npos) << "case '" << c.to << "' gave:\n" << msg;
    }
  }
}

TEST(AdaptiveProtocol, QuestPlusProblems) {
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"count = 16 }", "count = 1 }",
       "phase[2].stimuli: expected { from = a, to = b, count = 2..1000"},
      {"slopes = [10, 20, 40]", "slopes = [10, 0]", "phase[2].slopes: slopes must be > 0"},
      {"slopes = [10, 20, 40]\n", "", "phase[2].slopes: missing"},
      {"stimuli = { from = 0.0", "stimuli = { from = -0.5",
       "phase[2].stimuli: 0.3 + -0.5 = -0.2 is below the smallest friction.mu_k"},
      {"fit = \"logistic\"", "fit = \"weibull\"",
       "phase[2].stimuli: fit = \"weibull\" needs stimulus differences > 0"},
      {"trials = 40", "trials = 40\nsteps = [1]", "phase[2].steps: unknown key"},
  };
  for (const auto& c : cases) {
    std::string text = std::string(kBase) + kStair + kQuest;
    const auto pos = text.find(c.from, text.find("quest-plus"));
    ASSERT_NE(pos, std::string::npos) << c.from;
    text.replace(pos, c.from.size(), c.to);
    try {
      ParseProtocol(text, "bad.toml");
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos)
          << "case '" << c.to << "' gave:\n"
          << e.what();
    }
  }
}

}  // namespace
}  // namespace hapticlab::protocols::adaptive_test
