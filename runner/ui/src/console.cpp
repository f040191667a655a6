// The experimenter console (screens.hpp): the session's state as a banner, progress, elapsed
// time and the estimate to the end, the trial under way or the next one with what lies where,
// the live traces of the recorded streams, timing and link health, the experimenter's
// buttons, and the modals (consent before the first trial, abort).

#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

#include "hapticlab/runner_ui/screens.hpp"
#include "screens_internal.hpp"

namespace hapticlab::runner::ui {
namespace {

using internal::FullWindow;
using internal::Record;
using internal::TextRecorded;

std::string Clock(double s) {
  const auto t = static_cast<long>(std::max(0.0, std::round(s)));
  return t >= 3600 ? fmt::format("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60)
                   : fmt::format("{}:{:02}", t / 60, t % 60);
}

bool KeyPressed(ImGuiKey key) {
  const int k = ImGui::GetKeyIndex(key);
  return k >= 0 && ImGui::IsKeyPressed(k, false);
}

// The banner: what the session is doing, in words and a colour per state.
void Banner(const ConsoleView& v, Drawn* drawn) {
  using S = ConsoleView::State;
  std::string id, text;
  ImU32 colour = IM_COL32(60, 60, 70, 255);
  if (v.paused) {
    id = "paused";
    text = "PAUSED - the participant sees \"Please wait\". Press Resume to continue.";
    colour = IM_COL32(190, 120, 20, 255);
  } else {
    switch (v.state) {
      case S::kStarting:
        id = "starting", text = "STARTING";
        break;
      case S::kConsent:
        id = "consent", text = "CONSENT - confirm it before the first trial";
        colour = IM_COL32(150, 60, 150, 255);
        break;
      case S::kPlaceSamples:
        id = "place", text = "PLACE SAMPLES: " + v.next_placement;
        colour = IM_COL32(200, 150, 0, 255);
        break;
      case S::kExploring:
        id = "exploring", text = "EXPLORING - the participant explores";
        colour = IM_COL32(40, 140, 70, 255);
        break;
      case S::kRating:
        id = "rating", text = "WAITING FOR THE PARTICIPANT'S RATING";
        colour = IM_COL32(40, 120, 150, 255);
        break;
      case S::kNext:
        id = "next", text = "BETWEEN TRIALS - next trial below";
        break;
      case S::kBreak:
        id = "break", text = fmt::format("BREAK - {:.0f} s left", std::ceil(v.break_remaining_s));
        colour = IM_COL32(40, 110, 190, 255);
        break;
    }
  }
  const ImVec2 sp = ImGui::GetCursorScreenPos();
  const float w = ImGui::GetContentRegionAvail().x;
  ImGui::GetWindowDrawList()->AddRectFilled(sp, ImVec2(sp.x + w, sp.y + 34), colour);
  ImGui::SetCursorScreenPos(ImVec2(sp.x + 8, sp.y + 6));
  ImGui::SetWindowFontScale(1.3f);
  TextRecorded(drawn, "state:" + id, text);
  ImGui::SetWindowFontScale(1.0f);
  ImGui::SetCursorScreenPos(ImVec2(sp.x, sp.y + 40));
}

void Progress(const ConsoleView& v, Drawn* drawn) {
  const ImVec2 pp = ImGui::GetCursorScreenPos();
  const float frac = v.total > 0 ? static_cast<float>(v.done) / static_cast<float>(v.total) : 0.f;
  ImGui::PushStyleColor(ImGuiCol_PlotHistogram, IM_COL32(60, 180, 90, 255));
  ImGui::ProgressBar(frac, ImVec2(-1, 24),
                     fmt::format("{} of {} rated trials", v.done, v.total).c_str());
  ImGui::PopStyleColor();
  Record(drawn, "progress", pp, ImVec2(pp.x + ImGui::GetContentRegionAvail().x, pp.y + 24));
  if (v.training_total > 0)
    TextRecorded(drawn, "training",
                 fmt::format("Training: {} of {} trials", v.training_done, v.training_total));
  TextRecorded(drawn, "phase", "Phase: " + v.phase);
  TextRecorded(drawn, "time",
               fmt::format("Elapsed {}   {}", Clock(v.elapsed_s),
                           v.eta_s < 0 ? std::string("remaining: estimated after the first trial")
                                       : fmt::format("about {} to the end ({})", Clock(v.eta_s),
                                                     v.eta_basis)));
}

void Traces(const ConsoleView& v, Drawn* drawn) {
  TextRecorded(drawn, "trace-source", "Live (recorded streams): " + v.trace_source);
  for (const auto& tr : v.traces) {
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float w = ImGui::GetContentRegionAvail().x;
    const std::string overlay =
        tr.values.empty()
            ? fmt::format("{}: {}", tr.label, tr.none.empty() ? "no data" : tr.none)
            : fmt::format("{}  {:.4f}  (t = {:.3f} s)", tr.label, tr.values.back(), tr.t_s);
    static const float kNone = 0;
    ImGui::PlotLines(fmt::format("##{}", tr.id).c_str(),
                     tr.values.empty() ? &kNone : tr.values.data(),
                     tr.values.empty() ? 1 : static_cast<int>(tr.values.size()), 0, overlay.c_str(),
                     FLT_MAX, FLT_MAX, ImVec2(w, 58));
    Record(drawn, "trace:" + tr.id, p, ImVec2(p.x + w, p.y + 58));
  }
}

void HealthLines(const ConsoleView& v, Drawn* drawn) {
  const Health& h = v.health;
  if (!h.valid) {
    TextRecorded(drawn, "timing", "Timing: no side has run yet");
    return;
  }
  const std::string late = h.virtual_clock
                               ? std::string("lateness not measured (virtual clock: simulated)")
                               : fmt::format("lateness p50 {:.1f} us, p99 {:.1f} us (this side)",
                                             h.late_p50_us, h.late_p99_us);
  TextRecorded(drawn, "timing",
               fmt::format("Timing (force loop): {}; deadline misses: {} this trial, {} this "
                           "session (vibration loop: {} / {})",
                           late, h.misses_trial, h.misses_session, h.vib_misses_trial,
                           h.vib_misses_session));
  TextRecorded(
      drawn, "link",
      fmt::format("Device link (session): {} lost reads, {} reads without new data, "
                  "{} disconnects, {} stale, {} NaN; {} recording overflows",
                  h.lost_reads, h.empty_reads, h.disconnects, h.stale, h.nan, h.overflows));
}

void Buttons(const ConsoleView& v, ConsoleAction* act, Drawn* drawn) {
  const ImVec2 bp = ImGui::GetCursorScreenPos();
  if (v.paused)
    act->resume = ImGui::Button("Resume", ImVec2(110, 30));
  else
    act->pause = ImGui::Button("Pause", ImVec2(110, 30));
  ImGui::SameLine();
  if (v.state == ConsoleView::State::kBreak)
    act->end_break = ImGui::Button("End break now", ImVec2(110, 30));
  else
    act->take_break = ImGui::Button("Break", ImVec2(110, 30));
  ImGui::SameLine();
  ImGui::PushStyleColor(ImGuiCol_Button, IM_COL32(170, 40, 40, 255));
  act->abort = ImGui::Button("Abort", ImVec2(110, 30));
  ImGui::PopStyleColor();
  Record(drawn, "buttons", bp, ImVec2(bp.x + 350, bp.y + 30));
}

// The place-samples step: what to put where, and the confirmation (button, Enter or Space on
// the console; the rating box's button is read by the session UI).
void PlaceSamples(const ConsoleView& v, ConsoleAction* act, Drawn* drawn) {
  ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(255, 210, 80, 255));
  ImGui::SetWindowFontScale(1.4f);
  TextRecorded(drawn, "place", "Place samples: " + v.next_placement);
  ImGui::SetWindowFontScale(1.0f);
  ImGui::PopStyleColor();
  const ImVec2 bp = ImGui::GetCursorScreenPos();
  ImGui::PushStyleColor(ImGuiCol_Button, IM_COL32(200, 150, 0, 255));
  if (!v.paused && ImGui::Button("Samples placed (Enter)", ImVec2(240, 34)))
    act->samples_placed = true;
  ImGui::PopStyleColor();
  Record(drawn, "samples-placed", bp, ImVec2(bp.x + 240, bp.y + 34));
  ImGui::SameLine();
  ImGui::TextUnformatted("or press the rating box's button");
  if (!v.paused && !act->samples_placed &&
      (KeyPressed(ImGuiKey_Enter) || KeyPressed(ImGuiKey_KeyPadEnter) ||
       KeyPressed(ImGuiKey_Space)))
    act->samples_placed = act->samples_placed_by_key = true;
}

void CenteredModal(const char* name, float width) {
  if (!ImGui::IsPopupOpen(name)) ImGui::OpenPopup(name);
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x / 2, size.y / 2), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(width, 0));
}

void ConsentModal(const ConsoleView& v, ConsoleAction* act, Drawn* drawn) {
  constexpr const char* kName = "Consent";
  CenteredModal(kName, 560);
  if (!ImGui::BeginPopupModal(kName, nullptr,
                              ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings))
    return;
  const ImVec2 mp = ImGui::GetWindowPos();
  TextRecorded(
      drawn, "consent-document",
      fmt::format("Consent document: {}, version {}", v.consent_document, v.consent_version));
  ImGui::TextWrapped(
      "Confirm that participant %s has read and signed this consent document before the "
      "first trial. Enter your experimenter code (not your name); it is stored with the "
      "consent event.",
      v.participant.c_str());
  std::array<char, 33> buf{};
  v.consent_code.copy(buf.data(), buf.size() - 1);
  if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
  const ImVec2 ip = ImGui::GetCursorScreenPos();
  const bool enter = ImGui::InputText("Experimenter code", buf.data(), buf.size(),
                                      ImGuiInputTextFlags_EnterReturnsTrue);
  Record(drawn, "consent-code", ip, ImVec2(ip.x + 360, ip.y + ImGui::GetFrameHeight()));
  if (std::string(buf.data()) != v.consent_code) act->consent_code = std::string(buf.data());
  if (!v.consent_error.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(255, 120, 120, 255));
    const ImVec2 ep = ImGui::GetCursorScreenPos();
    ImGui::TextWrapped("%s", v.consent_error.c_str());
    Record(drawn, "consent-error", ep,
           ImVec2(ep.x + ImGui::GetContentRegionAvail().x, ImGui::GetCursorScreenPos().y));
    ImGui::PopStyleColor();
  }
  const ImVec2 cp = ImGui::GetCursorScreenPos();
  act->consent_confirmed = ImGui::Button("Confirm consent", ImVec2(200, 32)) || enter;
  Record(drawn, "consent-confirm", cp, ImVec2(cp.x + 200, cp.y + 32));
  ImGui::SameLine();
  ImGui::PushStyleColor(ImGuiCol_Button, IM_COL32(170, 40, 40, 255));
  act->abort = ImGui::Button("Abort", ImVec2(120, 32));
  ImGui::PopStyleColor();
  Record(drawn, "consent-modal", mp,
         ImVec2(mp.x + ImGui::GetWindowWidth(), mp.y + ImGui::GetWindowHeight()));
  ImGui::EndPopup();
}

void AbortModal(ConsoleAction* act, Drawn* drawn) {
  constexpr const char* kName = "Abort the session?";
  CenteredModal(kName, 460);
  if (!ImGui::BeginPopupModal(kName, nullptr,
                              ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings))
    return;
  const ImVec2 mp = ImGui::GetWindowPos();
  ImGui::TextWrapped(
      "Abort this session now? Completed trials stay recorded; the current trial is "
      "not. 'hapticlab study resume' continues with it later.");
  ImGui::Spacing();
  const ImVec2 yp = ImGui::GetCursorScreenPos();
  ImGui::PushStyleColor(ImGuiCol_Button, IM_COL32(170, 40, 40, 255));
  act->abort_confirmed = ImGui::Button("Abort session", ImVec2(200, 32));
  ImGui::PopStyleColor();
  Record(drawn, "abort-confirm", yp, ImVec2(yp.x + 200, yp.y + 32));
  ImGui::SameLine();
  const ImVec2 np = ImGui::GetCursorScreenPos();
  act->abort_cancelled = ImGui::Button("Continue", ImVec2(200, 32));
  Record(drawn, "abort-cancel", np, ImVec2(np.x + 200, np.y + 32));
  Record(drawn, "abort-modal", mp,
         ImVec2(mp.x + ImGui::GetWindowWidth(), mp.y + ImGui::GetWindowHeight()));
  ImGui::EndPopup();
}

// A modal closed from outside (the session moved on): close its popup too.
void CloseIfOpen(const char* name) {
  if (ImGui::IsPopupOpen(name) && ImGui::BeginPopupModal(name)) {
    ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
}

}  // namespace

ConsoleAction DrawConsole(const ConsoleView& v, Drawn* drawn) {
  ConsoleAction act;
  FullWindow("console", IM_COL32(32, 34, 40, 255));
  TextRecorded(drawn, "title", fmt::format("Study {}   participant {}", v.study, v.participant));
  Banner(v, drawn);
  Progress(v, drawn);
  const bool ahead =
      v.state != ConsoleView::State::kExploring && v.state != ConsoleView::State::kRating;
  if (!v.now.empty()) TextRecorded(drawn, "current", (ahead ? "Next: " : "Now: ") + v.now);
  if (v.state == ConsoleView::State::kPlaceSamples) {
    PlaceSamples(v, &act, drawn);
  } else if (!v.next_placement.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(255, 210, 80, 255));
    TextRecorded(drawn, "next", (ahead ? "Samples then: " : "Samples now: ") + v.next_placement);
    ImGui::PopStyleColor();
  }
  ImGui::Separator();
  Traces(v, drawn);
  HealthLines(v, drawn);
  ImGui::Separator();
  Buttons(v, &act, drawn);
  ImGui::Separator();
  TextRecorded(drawn, "device", "Device: " + v.device_status);
  std::string faults;
  for (const auto& [k, n] : v.faults)
    faults += fmt::format("{}{} {}", faults.empty() ? "" : ", ", k, n);
  TextRecorded(drawn, "faults", "Faults: " + (faults.empty() ? std::string("none") : faults));
  ImGui::Separator();
  for (std::size_t i = v.log.size() > 6 ? v.log.size() - 6 : 0; i < v.log.size(); ++i)
    ImGui::TextUnformatted(v.log[i].c_str());
  // Modals over the console (nothing else in it reacts while one is open): abort asks first;
  // consent before the first trial.
  if (v.confirm_abort) {
    act.abort = act.samples_placed = act.samples_placed_by_key = false;
    AbortModal(&act, drawn);
  } else {
    CloseIfOpen("Abort the session?");
    if (v.state == ConsoleView::State::kConsent) ConsentModal(v, &act, drawn);
  }
  if (v.state != ConsoleView::State::kConsent) CloseIfOpen("Consent");
  ImGui::End();
  return act;
}

}  // namespace hapticlab::runner::ui
