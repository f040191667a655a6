#pragma once
/// @file SessionUi on the two windows (ui_windows.hpp): the participant explores and rates, the
/// experimenter watches the console and can pause, call a break or abort.

#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "hapticlab/devices/device.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/runner_ui/ui_windows.hpp"

namespace hapticlab::runner::ui {

class WindowSessionUi final : public SessionUi {
 public:
  /// @throws std::runtime_error without a display
  /// @param box optional rating box: turning its knob sets the focused scale (the first at the
  ///        start), a press moves to the next one and, on the last with all set, confirms.
  WindowSessionUi(const std::string& study, const std::string& participant,
                  const std::string& device_status, const WindowOptions& o = {},
                  devices::RatingInput* box = nullptr);
  bool Stimulus(const TrialScreen& t, int side, const Eigen::Vector3d& stylus_m,
                double remaining_s) override;
  std::optional<std::vector<double>> Rate(const TrialScreen& t) override;
  /// Adaptive trials: a click, a number key (Y / N) or the rating box (the knob points at an
  /// answer, a press confirms it).
  std::optional<int> Choose(const TrialScreen& t) override;
  bool Break(double seconds) override;
  void Event(const std::string& line) override;
  bool TakeBreakNow() override {
    const bool b = break_requested_;
    break_requested_ = false;
    return b;
  }
  /// The traces and the timing / link health on the console.
  void Live(const LiveFrame& f) override;
  /// Shows `next` as the next trial (during breaks, placement and right after a rating).
  void Upcoming(const TrialScreen& next) override;
  /// "Place samples: left = real Denim, right = virtual" until the experimenter clicks
  /// "Samples placed", presses Enter or Space on the console, or presses the rating box's
  /// button; the participant is asked to wait meanwhile.
  std::optional<std::string> ConfirmPlacement(const TrialScreen& t) override;
  /// The consent modal: the document and version, an experimenter code field; returns the
  /// code once confirmed (2 to 16 letters, digits or '-', with at least one digit, so that a
  /// name is not taken for a code), nullopt once an abort is confirmed.
  std::optional<std::string> ConfirmConsent(const ConsentRequest& r) override;
  /// The console's state as last drawn (tests).
  const ConsoleView& console() const { return cv_; }
  /// A scripted experimenter (tests): called after every frame with the console's state and
  /// what it drew; the actions it returns are merged with the mouse's.
  using ConsoleScript = std::function<ConsoleAction(const ConsoleView&, const Drawn&)>;
  void SetConsoleScript(ConsoleScript script) { script_ = std::move(script); }
  /// Writes the last frame of window 0 (participant) or 1 (console) as PNG.
  void SaveScreenshot(int window, const std::string& path) const {
    win_.SaveScreenshot(window, path);
  }

 private:
  // One frame of both windows. Abort (or closing a window) opens the console's confirmation
  // and holds the session, as Pause does, until it is answered; a requested break is noted
  // for the runner. Returns false once the abort is confirmed.
  bool Frame(ParticipantAction* pa = nullptr);
  void Show(const TrialScreen& t);
  void Log(db::EventKind kind, const std::string& detail);
  void UpdateTimes();
  // A press of the rating box's button since the last call (edge), when it reports one.
  bool BoxPressed();
  TrialScreen next_;  // the last Upcoming
  std::chrono::steady_clock::time_point opened_ = std::chrono::steady_clock::now();
  std::optional<std::chrono::steady_clock::time_point> last_upcoming_;
  double break_s_since_ = 0;  // break time since the last Upcoming [s]
  double trial_s_sum_ = 0;    // wall time of the trials measured so far [s]
  int trials_timed_ = 0;
  // Live traces: the side they show, and the totals of the sides that ended.
  int live_plan_ = -1, live_side_ = -1;
  bool live_closed_ = true;
  double live_force_t_ = -1, live_vib_t_ = -1;
  Health closed_;  // counters of ended sides (this session; misses_trial: this trial)
  // What the experimenter did in the last frames, consumed by the waiting loops.
  bool placed_ = false, placed_by_key_ = false, consent_confirm_ = false;
  ConsoleScript script_;
  bool end_break_ = false;
  Windows win_;
  ParticipantView pv_;
  ConsoleView cv_;
  bool break_requested_ = false;
  devices::RatingInput* box_ = nullptr;
  bool box_button_ = false;  // last state, for edges
  double box_pos_ = -1;      // last knob position; -1: none yet
  std::size_t focus_ = 0;    // the scale the knob sets
};

}  // namespace hapticlab::runner::ui
