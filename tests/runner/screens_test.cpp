// The participant window's and the console's logic, headless (an ImGui frame without a GPU):
// scales have no default position, confirm needs every criterion, clicks set values, the
// console's buttons report.

#include "hapticlab/runner_ui/screens.hpp"

#include <gtest/gtest.h>
#include <imgui.h>

namespace hapticlab::runner::ui::screens_test {
namespace {

class Headless : public ::testing::Test {
 protected:
  void SetUp() override {
    ctx_ = ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    io.DisplaySize = ImVec2(1280, 800);
    io.DeltaTime = 1.f / 60;
    unsigned char* px;
    int w, h;
    io.Fonts->GetTexDataAsRGBA32(&px, &w, &h);  // builds the font atlas; no texture upload needed
  }
  void TearDown() override { ImGui::DestroyContext(ctx_); }
  // One frame with the mouse at (x, y), button down or up.
  ParticipantAction Frame(const ParticipantView& v, float x, float y, bool down,
                          Drawn* d = nullptr) {
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(x, y);
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    const auto a = DrawParticipant(v, d);
    ImGui::Render();
    return a;
  }
  ParticipantAction Click(ParticipantView& v, float x, float y) {
    Frame(v, x, y, false);
    auto a = Frame(v, x, y, true);
    v.ratings = a.ratings;
    a = Frame(v, x, y, false);
    v.ratings = a.ratings;
    return a;
  }
  ImGuiContext* ctx_ = nullptr;
};

TEST_F(Headless, RatingNeedsEveryCriterionAndStartsWithoutAValue) {
  ParticipantView v;
  v.mode = ParticipantView::Mode::kRating;
  v.criteria = {"roughness", "overall similarity"};
  Drawn d;
  auto a = Frame(v, -1, -1, false, &d);
  ASSERT_EQ(a.ratings.size(), 2u);
  EXPECT_FALSE(a.ratings[0] || a.ratings[1]) << "no default position";
  const auto* s1 = Find(d, "scale:roughness");
  const auto* s2 = Find(d, "scale:overall similarity");
  const auto* confirm = Find(d, "confirm");
  ASSERT_TRUE(s1 && s2 && confirm && Find(d, "label:roughness") && Find(d, "left-square") &&
              Find(d, "cursor"));
  // Confirm is inert before every scale is set.
  a = Click(v, confirm->cx(), confirm->cy());
  EXPECT_FALSE(a.confirmed);
  a = Click(v, s1->x0 + 0.75f * (s1->x1 - s1->x0), s1->cy());
  ASSERT_TRUE(a.ratings[0].has_value());
  EXPECT_NEAR(*a.ratings[0], 75, 0.5);
  EXPECT_FALSE(a.ratings[1].has_value());
  a = Click(v, confirm->cx(), confirm->cy());
  EXPECT_FALSE(a.confirmed);
  a = Click(v, s2->x0 + 0.2f * (s2->x1 - s2->x0), s2->cy());
  EXPECT_NEAR(*a.ratings[1], 20, 0.5);
  a = Click(v, confirm->cx(), confirm->cy());
  EXPECT_TRUE(a.confirmed);
  EXPECT_NEAR(*a.ratings[0], 75, 0.5) << "values survive the confirm";
}

TEST_F(Headless, SceneMapsTheWorkspaceAndBreaksShowACountdown) {
  ParticipantView v;
  v.left_square_m = {-0.03, 0};
  v.right_square_m = {0.03, 0};
  v.stylus_m = {0.03, 0.0, -0.001};  // on the right sample
  Drawn d;
  Frame(v, -1, -1, false, &d);
  const auto *l = Find(d, "left-square"), *r = Find(d, "right-square"), *c = Find(d, "cursor");
  ASSERT_TRUE(l && r && c);
  EXPECT_LT(l->cx(), 640);
  EXPECT_GT(r->cx(), 640);
  EXPECT_NEAR(c->cx(), r->cx(), 1.0);
  EXPECT_NEAR(c->cy(), r->cy(), 1.0);
  EXPECT_NEAR(l->cy(), 400, 1.0) << "y = 0 is the middle of the full-window scene";
  // The squares are named under them; at the workspace's far edge, below the phase's
  // prompt, the cursor is drawn whole (not clipped at the window's top).
  EXPECT_TRUE(Find(d, "name:left-square") && Find(d, "name:right-square"));
  v.stimulus_prompt = "Explore A, then B";
  v.stylus_m = {0.0, 0.04, 0.0};
  d.clear();
  Frame(v, -1, -1, false, &d);
  const auto *prompt = Find(d, "stimulus-prompt"), *top = Find(d, "cursor");
  ASSERT_TRUE(prompt && top);
  EXPECT_GE(top->y0, prompt->y1);
  v.stylus_m = {0.0, 0.2, 0.0};  // far outside the workspace: still whole on the screen
  d.clear();
  Frame(v, -1, -1, false, &d);
  EXPECT_GE(Find(d, "cursor")->y0, prompt->y1);
  v.mode = ParticipantView::Mode::kBreak;
  v.break_remaining_s = 41.2;
  d.clear();
  Frame(v, -1, -1, false, &d);
  EXPECT_TRUE(Find(d, "break"));
  EXPECT_FALSE(Find(d, "left-square"));
}

TEST_F(Headless, ConsoleButtonsReport) {
  ConsoleView v;
  v.study = "ch5";
  v.participant = "P01";
  v.done = 3;
  v.total = 10;
  v.traces = {{.id = "normal",
               .label = "normal force [N]",
               .values = {0.1f, 0.5f, 1.0f},
               .t_s = 0.1,
               .none = ""}};
  v.faults = {{"stale", 2}};
  auto frame = [&](float x, float y, bool down, Drawn* d) {
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(x, y);
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    const auto a = DrawConsole(v, d);
    ImGui::Render();
    return a;
  };
  Drawn d;
  frame(-1, -1, false, &d);
  const auto* b = Find(d, "buttons");
  ASSERT_TRUE(b && Find(d, "progress") && Find(d, "timing") && Find(d, "faults"));
  // Abort is the third button (110 px each, default spacing).
  const float ax = b->x0 + 2 * 110 + 2 * ImGui::GetStyle().ItemSpacing.x + 50, ay = b->cy();
  const float bx = b->x0 + 110 + ImGui::GetStyle().ItemSpacing.x + 50;  // the second button
  frame(ax, ay, false, nullptr);
  frame(ax, ay, true, nullptr);
  const auto a = frame(ax, ay, false, nullptr);
  EXPECT_TRUE(a.abort);
  EXPECT_FALSE(a.pause);
  // Abort only asks: the console then draws the confirmation, whose buttons answer it.
  v.confirm_abort = true;
  d.clear();
  frame(-1, -1, false, &d);
  d.clear();
  frame(-1, -1, false, &d);
  const auto *yes = Find(d, "abort-confirm"), *no = Find(d, "abort-cancel");
  ASSERT_TRUE(yes && no);
  frame(no->cx(), no->cy(), false, nullptr);
  frame(no->cx(), no->cy(), true, nullptr);
  const auto c = frame(no->cx(), no->cy(), false, nullptr);
  EXPECT_TRUE(c.abort_cancelled);
  EXPECT_FALSE(c.abort_confirmed);
  frame(yes->cx(), yes->cy(), false, nullptr);
  frame(yes->cx(), yes->cy(), true, nullptr);
  const auto y = frame(yes->cx(), yes->cy(), false, nullptr);
  EXPECT_TRUE(y.abort_confirmed);
  // While the modal is open the console's own buttons do not react.
  frame(ax, ay, false, nullptr);
  frame(ax, ay, true, nullptr);
  EXPECT_FALSE(frame(ax, ay, false, nullptr).abort);
  // A break: the countdown on the console and "End break now" where Break was.
  v.confirm_abort = false;
  v.state = ConsoleView::State::kBreak;
  v.break_remaining_s = 12.3;
  d.clear();
  frame(-1, -1, false, &d);
  ASSERT_TRUE(Find(d, "state:break"));
  const auto* b2 = Find(d, "buttons");
  ASSERT_TRUE(b2);
  frame(bx, b2->cy(), false, nullptr);
  frame(bx, b2->cy(), true, nullptr);
  const auto e = frame(bx, b2->cy(), false, nullptr);
  EXPECT_TRUE(e.end_break);
  EXPECT_FALSE(e.take_break);
}

}  // namespace
}  // namespace hapticlab::runner::ui::screens_test

namespace hapticlab::runner::ui::screens_test {
namespace {

// Adaptive trials: one button per answer; a click or a number key answers, nothing else does.
TEST_F(Headless, ChoiceAnswersByClickOrKey) {
  ParticipantView v;
  v.mode = ParticipantView::Mode::kChoice;
  v.question = "Which interval differed?";
  v.answers = {"1", "2", "3"};
  Drawn d;
  auto a = Frame(v, -1, -1, false, &d);
  EXPECT_FALSE(a.chosen) << "no default answer";
  const auto* b1 = Find(d, "answer:1");
  ASSERT_TRUE(b1 && Find(d, "answer:0") && Find(d, "answer:2") && Find(d, "prompt"));
  EXPECT_FALSE(Find(d, "answer:3"));
  Frame(v, b1->cx(), b1->cy(), false);
  Frame(v, b1->cx(), b1->cy(), true);
  a = Frame(v, b1->cx(), b1->cy(), false);
  ASSERT_TRUE(a.chosen);
  EXPECT_EQ(*a.chosen, 1);
  ImGui::GetIO().KeysDown['3'] = true;
  a = Frame(v, -1, -1, false);
  ImGui::GetIO().KeysDown['3'] = false;
  ASSERT_TRUE(a.chosen);
  EXPECT_EQ(*a.chosen, 2);
}

}  // namespace
}  // namespace hapticlab::runner::ui::screens_test

namespace hapticlab::runner::ui::screens_test {
namespace {

// Placing samples: the console names what goes where; the button or Enter on the console
// confirms, only in that state and not while paused.
TEST_F(Headless, PlaceSamplesConfirmsByButtonOrEnterOnly) {
  ConsoleView v;
  v.state = ConsoleView::State::kPlaceSamples;
  v.next_placement = "left = real Denim, right = virtual";
  auto frame = [&](float x, float y, bool down, Drawn* d) {
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(x, y);
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    const auto a = DrawConsole(v, d);
    ImGui::Render();
    return a;
  };
  Drawn d;
  EXPECT_FALSE(frame(-1, -1, false, &d).samples_placed) << "nothing placed by itself";
  ASSERT_TRUE(Find(d, "state:place") && Find(d, "place"));
  const auto* btn = Find(d, "samples-placed");
  ASSERT_TRUE(btn);
  frame(btn->cx(), btn->cy(), false, nullptr);
  frame(btn->cx(), btn->cy(), true, nullptr);
  auto a = frame(btn->cx(), btn->cy(), false, nullptr);
  EXPECT_TRUE(a.samples_placed);
  EXPECT_FALSE(a.samples_placed_by_key);
  ImGuiIO& io = ImGui::GetIO();
  constexpr int kEnter = 257;  // GLFW_KEY_ENTER, as ui_windows.cpp maps it
  io.KeyMap[ImGuiKey_Enter] = kEnter;
  io.KeysDown[kEnter] = true;
  a = frame(-1, -1, false, nullptr);
  io.KeysDown[kEnter] = false;
  EXPECT_TRUE(a.samples_placed && a.samples_placed_by_key);
  frame(-1, -1, false, nullptr);
  // Paused: neither confirms. In another state Enter places nothing.
  v.paused = true;
  io.KeysDown[kEnter] = true;
  EXPECT_FALSE(frame(-1, -1, false, nullptr).samples_placed);
  io.KeysDown[kEnter] = false;
  frame(-1, -1, false, nullptr);
  v.paused = false;
  v.state = ConsoleView::State::kExploring;
  io.KeysDown[kEnter] = true;
  EXPECT_FALSE(frame(-1, -1, false, nullptr).samples_placed);
  io.KeysDown[kEnter] = false;
}

}  // namespace
}  // namespace hapticlab::runner::ui::screens_test
