// The participant window and the console (runner/ui/src/ui_windows.cpp) rendered for a fixed
// state in real OpenGL windows (under Xvfb in CI), saved as PNGs and checked pixel by pixel:
// the squares and the cursor where the layout put them, text present in every label's box.
// Built with session_ui_test.cpp into one executable that runs under Xvfb
// (tests/CMakeLists.txt, ctest name Screenshot.ParticipantWindowAndConsole).

#include "hapticlab/runner_ui/ui_windows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <utility>

#include "screenshot_util.hpp"

namespace hapticlab::runner::ui::ui_windows_test {
namespace {

using test_screens::Bright;

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
  cv.state = ConsoleView::State::kExploring;
  cv.now = "trial 9: real:Wood | virtual:Wood (Hybrid)";
  cv.next_placement = "left = real Wood, right = virtual";
  cv.done = 6;
  cv.total = 60;
  cv.training_done = 10;
  cv.training_total = 10;
  for (const auto& [id, label] : {std::pair{"normal", "normal force [N]"},
                                  {"tangential", "tangential force [N]"},
                                  {"speed", "tangential speed [m/s]"},
                                  {"vibration", "vibration command [m/s^2]"}}) {
    Trace tr{.id = id, .label = label, .values = {}, .t_s = 1.5, .none = ""};
    for (int k = 0; k < 200; ++k)
      tr.values.push_back(1.0f + 0.3f * std::sin(static_cast<float>(k) * 0.1f));
    cv.traces.push_back(tr);
  }
  cv.health = {
      .valid = true, .late_p50_us = 12, .late_p99_us = 48, .misses_trial = 1, .misses_session = 3};
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
       {"title", "next", "phase", "time", "device", "faults", "trace:normal", "trace:tangential",
        "trace:speed", "trace:vibration", "timing", "link", "state:exploring"}) {
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

}  // namespace
}  // namespace hapticlab::runner::ui::ui_windows_test
