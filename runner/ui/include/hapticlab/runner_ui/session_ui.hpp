#pragma once
/// @file SessionUi on the two windows (ui_windows.hpp): the participant explores and rates, the
/// experimenter watches the console and can pause, call a break or abort.

#include <deque>
#include <functional>
#include <memory>
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
  void Log(const std::string& kind, const std::string& detail);
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
