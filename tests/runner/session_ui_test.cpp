// The session UI on the two windows (runner/ui/src/session_ui.cpp) under Xvfb: the console's
// abort confirmation, pause and break, and a rating box driving the participant's scales.
// Built with ui_windows_test.cpp into one executable that runs under Xvfb (tests/CMakeLists.txt).

#include "hapticlab/runner_ui/session_ui.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

#include "hapticlab/runner_ui/ui_windows.hpp"
#include "screenshot_util.hpp"

namespace hapticlab::runner::ui::session_ui_test {
namespace {

using test_screens::Bright;

// A rating box scripted report by report: knob to 0.3, press, knob to 0.8, press.
class ScriptedBox : public devices::RatingInput {
 public:
  devices::RatingEvent Poll() override {
    static const devices::RatingEvent script[] = {{true, 0.3, false}, {true, 0.3, true},
                                                  {true, 0.3, false}, {true, 0.8, false},
                                                  {true, 0.8, true},  {true, 0.8, false}};
    return k_ < std::size(script) ? script[k_++] : devices::RatingEvent{};
  }

 private:
  std::size_t k_ = 0;
};

// The console's Abort asks first (the modal drawn, its buttons readable): Continue keeps the
// session running, a second Abort confirmed stops it (the runner then records the stop and
// 'study run' exits 3: tests/apps/cmd_study_test.cpp). Pause and an early-ended break show
// their state on the console, and every one of these actions is logged as an event.
TEST(Screenshot, AbortAsksForConfirmationAndPauseAndBreakShowTheirState) {
  const std::string out = std::string(HL_BINARY_DIR) + "/screenshots";
  std::filesystem::create_directories(out);
  WindowSessionUi ui("s", "P01", "test", {.width = 900, .height = 650});
  std::vector<std::string> events;
  ui.log_event = [&](db::EventKind kind, const std::string&) {
    events.emplace_back(NameOf(db::kEventKindNames, kind));
  };
  TrialScreen t;
  t.index = 3;
  t.total = 20;
  t.rated_done = 2;
  t.rated_total = 20;
  t.criteria = {"roughness"};
  std::string answer;  // what the scripted experimenter does once the state is shown
  bool asked = false, shown = false;
  int frames = 0, modal_frames = 0;
  ui.SetConsoleScript([&](const ConsoleView& cv, const Drawn& d) {
    ConsoleAction a;
    ++frames;
    if (answer == "cancel" || answer == "confirm") {
      if (!asked) {
        a.abort = asked = true;
      } else if (cv.confirm_abort && Find(d, "abort-confirm") && Find(d, "abort-cancel") &&
                 ++modal_frames >= 3) {
        // (ImGui sizes a new popup on its first frame and shows it from the next.)
        if (!shown) {
          ui.SaveScreenshot(1, out + "/console-abort.png");
          const cv::Mat c = cv::imread(out + "/console-abort.png");
          EXPECT_GT(Bright(c, *Find(d, "abort-confirm")), 15) << "the confirm button has its text";
          EXPECT_GT(Bright(c, *Find(d, "abort-cancel")), 15) << "the cancel button has its text";
        }
        shown = true;
        (answer == "cancel" ? a.abort_cancelled : a.abort_confirmed) = true;
      }
    } else if (answer == "pause") {
      if (!cv.paused && !shown)
        a.pause = true;
      else if (cv.paused && Find(d, "state:paused")) {
        shown = true;
        a.resume = true;
      }
    } else if (answer == "end break") {
      if (cv.state == ConsoleView::State::kBreak && Find(d, "state:break")) {
        shown = true;
        a.end_break = true;
      }
    }
    return a;
  });
  const auto step = [&](const std::string& what) {
    answer = what;
    asked = shown = false;
    frames = modal_frames = 0;
  };
  step("cancel");
  EXPECT_TRUE(ui.Stimulus(t, 0, Eigen::Vector3d::Zero(), 1.0))
      << "Continue keeps the session running";
  EXPECT_TRUE(shown) << "the confirmation was drawn";
  step("pause");
  EXPECT_TRUE(ui.Stimulus(t, 0, Eigen::Vector3d::Zero(), 1.0));
  EXPECT_TRUE(shown) << "the PAUSED state was drawn";
  step("end break");
  EXPECT_TRUE(ui.Break(600.0)) << "ended early, not aborted";
  EXPECT_TRUE(shown) << "the break's countdown was drawn";
  EXPECT_LT(frames, 100) << "the break ended when asked";
  step("confirm");
  EXPECT_FALSE(ui.Stimulus(t, 1, Eigen::Vector3d::Zero(), 1.0))
      << "a confirmed abort stops the session";
  EXPECT_TRUE(shown);
  const std::vector<std::string> expected = {
      "abort-requested", "abort-cancelled", "pause",          "resume",
      "break-ended",     "abort-requested", "abort-confirmed"};
  EXPECT_EQ(events, expected);
}

TEST(Screenshot, RatingBoxDrivesTheParticipantWindow) {
  ScriptedBox box;
  WindowSessionUi ui("s", "P01", "test", {.width = 800, .height = 600}, &box);
  TrialScreen t;
  t.index = 1;
  t.total = 1;
  t.criteria = {"roughness", "overall"};
  const auto r = ui.Rate(t);
  ASSERT_TRUE(r.has_value());
  ASSERT_EQ(r->size(), 2u);
  EXPECT_NEAR((*r)[0], 30, 1e-9);
  EXPECT_NEAR((*r)[1], 80, 1e-9);
}

}  // namespace
}  // namespace hapticlab::runner::ui::session_ui_test
