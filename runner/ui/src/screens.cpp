#include "hapticlab/runner_ui/screens.hpp"

#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <tuple>

#include "screens_internal.hpp"

namespace hapticlab::runner::ui {
namespace {

constexpr ImU32 kWhite = IM_COL32(255, 255, 255, 255);
constexpr ImU32 kTrack = IM_COL32(150, 150, 150, 255);
constexpr ImU32 kHandle = IM_COL32(80, 170, 255, 255);

}  // namespace

namespace internal {

void Record(Drawn* d, const std::string& id, ImVec2 a, ImVec2 b) {
  if (d) d->push_back({id, a.x, a.y, b.x, b.y});
}

void FullWindow(const char* name, ImU32 bg) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(io.DisplaySize);
  ImGui::PushStyleColor(ImGuiCol_WindowBg, bg);
  ImGui::Begin(name, nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus);
  ImGui::PopStyleColor();
}

// A rating scale with no default position: a track the participant clicks or drags on; the
// handle appears only once a value is set.
bool RatingScale(const std::string& id, std::optional<double>* value, double lo, double hi,
                 float width, Drawn* drawn) {
  const ImVec2 p = ImGui::GetCursorScreenPos();
  const float h = 28;
  ImGui::InvisibleButton(id.c_str(), ImVec2(width, h));
  bool changed = false;
  if (ImGui::IsItemActive()) {
    const float t = std::clamp((ImGui::GetIO().MousePos.x - p.x) / width, 0.f, 1.f);
    *value = lo + (hi - lo) * t;
    changed = true;
  }
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float y = p.y + h / 2;
  dl->AddLine(ImVec2(p.x, y), ImVec2(p.x + width, y), kTrack, 3);
  for (int k = 0; k <= 10; ++k) {
    const float x = p.x + width * static_cast<float>(k) / 10;
    dl->AddLine(ImVec2(x, y - (k % 5 ? 4.f : 8.f)), ImVec2(x, y + (k % 5 ? 4.f : 8.f)), kTrack, 2);
  }
  if (*value) {
    const float x = p.x + width * static_cast<float>((**value - lo) / (hi - lo));
    dl->AddCircleFilled(ImVec2(x, y), 9, kHandle);
  }
  Record(drawn, "scale:" + id, p, ImVec2(p.x + width, p.y + h));
  return changed;
}

void TextRecorded(Drawn* d, const std::string& id, const std::string& text) {
  const ImVec2 p = ImGui::GetCursorScreenPos();
  ImGui::TextUnformatted(text.c_str());
  const ImVec2 sz = ImGui::CalcTextSize(text.c_str());
  Record(d, id, p, ImVec2(p.x + sz.x, p.y + sz.y));
}

}  // namespace internal

using internal::FullWindow;
using internal::RatingScale;
using internal::Record;
using internal::TextRecorded;

const DrawnItem* Find(const Drawn& d, const std::string& id) {
  for (const auto& x : d)
    if (x.id == id) return &x;
  return nullptr;
}

namespace {

using Mode = ParticipantView::Mode;

// A break or a message, centred; the whole window.
void DrawMessage(const ParticipantView& v, ImVec2 size, Drawn* drawn) {
  const std::string text =
      v.mode == Mode::kBreak
          ? fmt::format("Break. Please rest your hand.\nThe study continues in {:.0f} s.",
                        std::ceil(v.break_remaining_s))
          : v.message;
  ImGui::SetWindowFontScale(2.0f);
  const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
  ImGui::SetCursorPos(ImVec2((size.x - ts.x) / 2, (size.y - ts.y) / 2));
  TextRecorded(drawn, v.mode == Mode::kBreak ? "break" : "message", text);
  ImGui::SetWindowFontScale(1.0f);
}

// The scene's height: the upper part of the window (all of it while the stimulus is
// explored). Rating: the panel under the scene holds the prompt, each criterion (gap, name,
// scale, end labels) and the confirm button; the scene gets what is left (at most 55 %).
float SceneHeight(const ParticipantView& v, ImVec2 size) {
  const bool below = v.mode == Mode::kRating || v.mode == Mode::kChoice;
  const ImGuiStyle& style = ImGui::GetStyle();
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const float per_criterion =
      14 + 1.25f * line + 28 + style.ItemSpacing.y + line + style.ItemSpacing.y;
  const float panel =
      v.mode == Mode::kRating
          ? 10 + line + static_cast<float>(v.criteria.size()) * per_criterion + 10 + 36 + 34
          : 130;
  return below ? std::max(size.y * 0.3f, std::min(size.y * 0.55f, size.y - panel)) : size.y;
}

// The two squares with their names, and the sphere cursor, between `top` and `scene_h`. The
// margins hold the whole cursor (a 6 mm sphere) wherever the stylus is, so it is never
// clipped at the window's edges.
void DrawScene(const ParticipantView& v, ImVec2 size, float top, float scene_h, Drawn* drawn) {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  constexpr double kCursorRadius_m = 0.006;
  const Eigen::Vector2d span = v.workspace_max_m - v.workspace_min_m;
  const float scale =
      std::min(size.x * 0.95f / static_cast<float>(span.x() + 2 * kCursorRadius_m),
               (scene_h - top) * 0.95f / static_cast<float>(span.y() + 2 * kCursorRadius_m));
  const ImVec2 origin((size.x - scale * static_cast<float>(span.x())) / 2,
                      top + (scene_h - top - scale * static_cast<float>(span.y())) / 2);
  auto to_px = [&](const Eigen::Vector2d& m) {
    // y of the device (away from the participant) goes up on the screen.
    return ImVec2(origin.x + scale * static_cast<float>(m.x() - v.workspace_min_m.x()),
                  origin.y + scale * static_cast<float>(v.workspace_max_m.y() - m.y()));
  };
  const float half = 0.5f * scale * static_cast<float>(v.square_size_m);
  for (const auto& [id, c, label] : {std::tuple{"left-square", v.left_square_m, v.left_label},
                                     std::tuple{"right-square", v.right_square_m, v.right_label}}) {
    if (!v.right_present && std::string(id) == "right-square") continue;
    const ImVec2 m = to_px(c);
    dl->AddRectFilled(ImVec2(m.x - half, m.y - half), ImVec2(m.x + half, m.y + half), kWhite);
    Record(drawn, id, ImVec2(m.x - half, m.y - half), ImVec2(m.x + half, m.y + half));
    // The square's name under it ("A" / "B"), as the prompts and the experimenter call them.
    ImGui::SetWindowFontScale(1.6f);
    const ImVec2 ls = ImGui::CalcTextSize(label.c_str());
    ImGui::SetCursorScreenPos(ImVec2(m.x - ls.x / 2, m.y + half + 6));
    TextRecorded(drawn, std::string("name:") + id, label);
    ImGui::SetWindowFontScale(1.0f);
  }
  // The sphere cursor: shaded disc, darker when pressing into the surface (z < 0); kept
  // whole inside the scene.
  const float r = std::max(6.f, static_cast<float>(kCursorRadius_m) * scale);
  ImVec2 cp = to_px(v.stylus_m.head<2>());
  cp.x = std::clamp(cp.x, r, std::max(r, size.x - r));
  cp.y = std::clamp(cp.y, top + r, std::max(top + r, scene_h - r));
  const float press = std::clamp(static_cast<float>(-v.stylus_m.z() / 0.002), 0.f, 1.f);
  const auto shade = [&](float k) {
    return IM_COL32(static_cast<int>((255 - 90 * press) * k),
                    static_cast<int>((140 - 60 * press) * k), static_cast<int>(30 * k), 255);
  };
  dl->AddCircleFilled(cp, r, shade(0.75f), 32);
  dl->AddCircleFilled(ImVec2(cp.x - r * 0.25f, cp.y - r * 0.25f), r * 0.6f, shade(1.0f), 32);
  Record(drawn, "cursor", ImVec2(cp.x - r, cp.y - r), ImVec2(cp.x + r, cp.y + r));
}

// The rating panel under the scene: the prompt, a scale per criterion, confirm.
void DrawRatingPanel(const ParticipantView& v, ImVec2 size, float scene_h, ParticipantAction& act,
                     Drawn* drawn) {
  const float width = std::min(700.f, size.x * 0.6f);
  const float x0 = (size.x - width) / 2;
  ImGui::SetCursorPos(ImVec2(x0, scene_h + 10));
  TextRecorded(drawn, "prompt",
               fmt::format("How similar are {} and {}? Click on each scale, then confirm.",
                           v.left_label, v.right_label));
  for (std::size_t i = 0; i < v.criteria.size(); ++i) {
    // One group per criterion: its name (larger) right above its scale, the scale's end
    // labels right under it, then a gap before the next criterion's name.
    ImGui::Dummy(ImVec2(0, i == 0 ? 4.f : 14.f));
    ImGui::SetCursorPosX(x0);
    ImGui::SetWindowFontScale(1.25f);
    TextRecorded(drawn, "label:" + v.criteria[i], v.criteria[i]);
    ImGui::SetWindowFontScale(1.0f);
    ImGui::SetCursorPosX(x0);
    RatingScale(v.criteria[i], &act.ratings[i], v.scale_min, v.scale_max, width, drawn);
    ImGui::SetCursorPosX(x0);
    ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(170, 170, 170, 255));
    TextRecorded(drawn, "low:" + v.criteria[i], v.scale_low);
    ImGui::SameLine(x0 + width - ImGui::CalcTextSize(v.scale_high.c_str()).x);
    TextRecorded(drawn, "high:" + v.criteria[i], v.scale_high);
    ImGui::PopStyleColor();
  }
  ImGui::Dummy(ImVec2(0, 10));
  const bool all = std::all_of(act.ratings.begin(), act.ratings.end(),
                               [](const auto& x) { return x.has_value(); });
  ImGui::SetCursorPosX(x0 + width / 2 - 60);
  if (!all) ImGui::BeginDisabled();
  const ImVec2 bp = ImGui::GetCursorScreenPos();
  if (ImGui::Button("Confirm", ImVec2(120, 36)) && all) act.confirmed = true;
  Record(drawn, "confirm", bp, ImVec2(bp.x + 120, bp.y + 36));
  if (!all) ImGui::EndDisabled();
}

// The question and one button per answer; number keys (and Y / N) answer too.
void DrawChoicePanel(const ParticipantView& v, ImVec2 size, float scene_h, ParticipantAction& act,
                     Drawn* drawn) {
  const float bw = 120, gap = 24;
  const float total = static_cast<float>(v.answers.size()) * (bw + gap) - gap;
  ImGui::SetCursorPos(
      ImVec2((size.x - ImGui::CalcTextSize(v.question.c_str()).x) / 2, scene_h + 10));
  TextRecorded(drawn, "prompt", v.question);
  ImGui::SetCursorPos(ImVec2((size.x - total) / 2, scene_h + 60));
  for (std::size_t k = 0; k < v.answers.size(); ++k) {
    if (k > 0) ImGui::SameLine(0, gap);
    const bool lit = static_cast<int>(k) == v.highlighted;
    if (lit) ImGui::PushStyleColor(ImGuiCol_Button, IM_COL32(80, 170, 255, 255));
    const ImVec2 bp = ImGui::GetCursorScreenPos();
    if (ImGui::Button(v.answers[k].c_str(), ImVec2(bw, 48))) act.chosen = static_cast<int>(k);
    if (lit) ImGui::PopStyleColor();
    Record(drawn, "answer:" + std::to_string(k), bp, ImVec2(bp.x + bw, bp.y + 48));
    const bool yes_no = v.answers.size() == 2 && v.answers[0] == "yes" && v.answers[1] == "no";
    if ((k < 9 && ImGui::IsKeyPressed('1' + static_cast<int>(k), false)) ||
        (yes_no && ImGui::IsKeyPressed(k == 0 ? 'Y' : 'N', false)))
      act.chosen = static_cast<int>(k);
  }
}

}  // namespace

ParticipantAction DrawParticipant(const ParticipantView& v, Drawn* drawn) {
  ParticipantAction act;
  act.ratings = v.ratings;
  act.ratings.resize(v.criteria.size());
  FullWindow("participant", IM_COL32(20, 20, 24, 255));
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  if (v.mode == Mode::kBreak || v.mode == Mode::kMessage) {
    DrawMessage(v, size, drawn);
    ImGui::End();
    return act;
  }
  const float scene_h = SceneHeight(v, size);
  float top = 0;  // below the phase's prompt
  if (v.mode == Mode::kStimulus && !v.stimulus_prompt.empty()) {
    ImGui::SetWindowFontScale(1.5f);
    const ImVec2 ts = ImGui::CalcTextSize(v.stimulus_prompt.c_str());
    ImGui::SetCursorPos(ImVec2((size.x - ts.x) / 2, 12));
    TextRecorded(drawn, "stimulus-prompt", v.stimulus_prompt);
    ImGui::SetWindowFontScale(1.0f);
    top = ts.y + 24;
  }
  DrawScene(v, size, top, scene_h, drawn);
  if (v.mode == Mode::kRating) DrawRatingPanel(v, size, scene_h, act, drawn);
  if (v.mode == Mode::kChoice) DrawChoicePanel(v, size, scene_h, act, drawn);
  if (v.trials > 0) {
    ImGui::SetCursorPos(ImVec2(10, size.y - 24));
    TextRecorded(drawn, "trial",
                 fmt::format("{}{} / {}", v.training ? "Training " : "", v.trial, v.trials));
  }
  ImGui::End();
  return act;
}

}  // namespace hapticlab::runner::ui
