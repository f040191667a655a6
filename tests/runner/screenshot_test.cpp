// The participant window and the console rendered for a fixed state in real OpenGL windows
// (under Xvfb in CI), saved as PNGs and checked pixel by pixel: the squares and the cursor
// where the layout put them, text present in every label's box.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

#include "hapticlab/runner_ui/session_ui.hpp"
#include "hapticlab/runner_ui/ui_windows.hpp"

namespace hapticlab::runner::ui {
namespace {

int Bright(const cv::Mat& img, const DrawnItem& r, int threshold = 140) {
  int n = 0;
  for (int y = static_cast<int>(r.y0); y < static_cast<int>(r.y1); ++y)
    for (int x = static_cast<int>(r.x0); x < static_cast<int>(r.x1); ++x) {
      if (x < 0 || y < 0 || x >= img.cols || y >= img.rows) continue;
      const auto p = img.at<cv::Vec3b>(y, x);
      if ((p[0] + p[1] + p[2]) / 3 > threshold) ++n;
    }
  return n;
}

TEST(Screenshot, ParticipantWindowAndConsole) {
  const std::string out = std::string(HL_BINARY_DIR) + "/screenshots";
  std::filesystem::create_directories(out);
  Windows w({.width = 1024, .height = 700});
  ParticipantView pv;
  pv.mode = ParticipantView::Mode::kRating;
  pv.criteria = {"roughness", "friction", "overall similarity"};
  pv.ratings = {62.0, std::nullopt, 35.0};
  pv.stylus_m = {-0.03, 0.005, -0.0005};
  pv.trial = 7;
  pv.trials = 60;
  ConsoleView cv;
  cv.study = "ch5-hybrid-realism";
  cv.participant = "P03";
  cv.phase = "main";
  cv.current = "trial 7: wood, hybrid (real left)";
  cv.next_placement = "sandpaper on the left, virtual on the right";
  cv.done = 6;
  cv.total = 60;
  cv.training_done = 10;
  cv.training_total = 10;
  for (int k = 0; k < 200; ++k) {
    cv.force_N.push_back(1.0f + 0.3f * std::sin(static_cast<float>(k) * 0.1f));
    cv.speed_mps.push_back(0.05f + 0.02f * std::sin(static_cast<float>(k) * 0.05f));
    cv.acc_mps2.push_back(std::sin(static_cast<float>(k) * 1.3f));
  }
  cv.device_status = "sim, 1000 Hz force, 10000 Hz vibration";
  cv.faults = {{"stale", 0}, {"disconnect", 0}};
  Drawn pd, cd;
  for (int f = 0; f < 3; ++f) {  // ImGui lays out on the first frame; take the third
    pd.clear();
    cd.clear();
    ASSERT_TRUE(w.Frame(pv, cv, nullptr, nullptr, &pd, &cd));
  }
  w.SaveScreenshot(0, out + "/participant.png");
  w.SaveScreenshot(1, out + "/console.png");
  const cv::Mat p = cv::imread(out + "/participant.png"), c = cv::imread(out + "/console.png");
  ASSERT_FALSE(p.empty());
  ASSERT_FALSE(c.empty());
  ASSERT_EQ(p.cols, 1024);
  // White squares: their centres are white, the background between them is dark.
  const auto *l = Find(pd, "left-square"), *r = Find(pd, "right-square"), *cur = Find(pd, "cursor");
  ASSERT_TRUE(l && r && cur);
  const auto px = [&](float x, float y) {
    return p.at<cv::Vec3b>(static_cast<int>(y), static_cast<int>(x));
  };
  const auto rc = px(r->cx(), r->cy());
  EXPECT_GT(rc[0], 240);
  EXPECT_GT(rc[1], 240);
  EXPECT_GT(rc[2], 240);
  const auto mid = px(0.5f * (l->x1 + r->x0), l->cy());
  EXPECT_LT(mid[0] + mid[1] + mid[2], 120);
  // The cursor is orange (BGR: little blue, much red) and sits on the left square.
  const auto cc =
      px(cur->cx() + 0.25f * (cur->x1 - cur->x0), cur->cy() + 0.25f * (cur->y1 - cur->y0));
  EXPECT_GT(cc[2], 120);
  EXPECT_LT(cc[0], 60);
  EXPECT_GT(cur->cx(), l->x0);
  EXPECT_LT(cur->cx(), l->x1);
  // Every label and the confirm button have text in their boxes.
  // Nothing drawn outside the window (the confirm button, the last scale's labels).
  for (const auto& it : pd) {
    EXPECT_GE(it.y0, 0) << it.id;
    EXPECT_LE(it.y1, 700) << it.id;
  }
  // Each criterion's name sits with its own scale: right above it, and clearly below the
  // previous scale's end labels.
  for (const auto& [prev, crit] :
       {std::pair{"roughness", "friction"}, std::pair{"friction", "overall similarity"}}) {
    const auto *label = Find(pd, std::string("label:") + crit),
               *scale = Find(pd, std::string("scale:") + crit);
    const auto* prev_end = Find(pd, std::string("high:") + prev);
    ASSERT_TRUE(label && scale && prev_end) << crit;
    EXPECT_LE(label->y1, scale->y0 + 1) << crit;
    EXPECT_LT(scale->y0 - label->y1, label->y0 - prev_end->y1)
        << crit << ": nearer its scale than the previous one";
  }
  for (const auto& id :
       {"label:roughness", "label:friction", "label:overall similarity", "low:roughness",
        "high:roughness", "prompt", "name:left-square", "name:right-square"}) {
    const auto* it = Find(pd, id);
    ASSERT_TRUE(it) << id;
    EXPECT_GT(Bright(p, *it), 15) << id;
  }
  for (const auto& id :
       {"title", "next", "phase", "device", "faults", "trace:force", "trace:speed", "trace:acc"}) {
    const auto* it = Find(cd, id);
    ASSERT_TRUE(it) << id;
    EXPECT_GT(Bright(c, *it), 15) << id;
  }
  // The progress bar is filled 6/60: green at its start, not at its end.
  const auto* pr = Find(cd, "progress");
  ASSERT_TRUE(pr);
  const auto g0 = c.at<cv::Vec3b>(static_cast<int>(pr->cy()), static_cast<int>(pr->x0 + 5));
  const auto g1 = c.at<cv::Vec3b>(static_cast<int>(pr->cy()), static_cast<int>(pr->x1 - 5));
  EXPECT_GT(g0[1], 150);
  EXPECT_LT(g1[1], 150);
}

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
  ui.log_event = [&](const std::string& kind, const std::string&) { events.push_back(kind); };
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
      if (cv.on_break && Find(d, "state:break")) {
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
}  // namespace hapticlab::runner::ui
