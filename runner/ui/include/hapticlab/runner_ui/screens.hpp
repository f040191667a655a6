#pragma once
/// @file The study's screens, drawn with Dear ImGui (dissertation ch. IV.5.1, V.2.1): the
/// participant window (two white squares where the real and the virtual sample lie, a sphere
/// cursor at the stylus, rating scales with no default position, a confirm button, the break
/// screen) and the experimenter console (progress through the plan, the next physical sample
/// to place, live force/speed/acceleration traces, pause/break/abort, device status and fault
/// counters). The draw functions only need an ImGui frame, so tests run them headless; the
/// windows (GLFW + OpenGL) are in ui_windows.hpp.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hapticlab::runner::ui {

/// One thing a screen drew, in window pixels (for tests and screenshot checks).
struct DrawnItem {
  std::string id;  ///< "left-square", "right-square", "cursor", "scale:<criterion>",
                   ///< "label:<criterion>", "confirm", ...
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  float cx() const { return 0.5f * (x0 + x1); }
  float cy() const { return 0.5f * (y0 + y1); }
};
using Drawn = std::vector<DrawnItem>;
const DrawnItem* Find(const Drawn& d, const std::string& id);

struct ParticipantView {
  enum class Mode { kStimulus, kRating, kBreak, kMessage, kChoice };
  Mode mode = Mode::kStimulus;
  // The scene, in the device's horizontal plane [m].
  Eigen::Vector2d workspace_min_m{-0.06, -0.04}, workspace_max_m{0.06, 0.04};
  Eigen::Vector2d left_square_m{-0.03, 0}, right_square_m{0.03, 0};
  double square_size_m = 0.03;
  Eigen::Vector3d stylus_m =
      Eigen::Vector3d::Zero();  ///< the cursor (z shades it: pressing darkens)
  // Rating.
  std::vector<std::string> criteria;
  std::vector<std::optional<double>> ratings;  ///< per criterion; unset: no handle drawn
  double scale_min = 0, scale_max = 100;
  std::string scale_low = "very different", scale_high = "identical";
  // Choice (adaptive trials): one button per answer, keys 1..9 (and Y / N for yes / no).
  std::string question;
  std::vector<std::string> answers;
  int highlighted = -1;  ///< the answer the rating box's knob points at (-1: none)
  // Break / message.
  double break_remaining_s = 0;
  std::string message;
  int trial = 0, trials = 0;  ///< 1-based rated trial of the main phases, and how many
  bool training = false;      ///< a training trial: `trial`/`trials` count the training trials
  /// The prompt above the squares while the participant explores (per phase), e.g.
  /// "Training: explore both samples"; empty: none.
  std::string stimulus_prompt;
  std::string left_label = "A", right_label = "B";  ///< under the squares
};

struct ParticipantAction {
  std::vector<std::optional<double>> ratings;  ///< after this frame's input
  bool confirmed = false;                      ///< confirm pressed with every criterion rated
  std::optional<int> chosen;                   ///< choice mode: the answer clicked or keyed
};

/// Draws the participant window into the current ImGui frame (full window).
ParticipantAction DrawParticipant(const ParticipantView& v, Drawn* drawn = nullptr);

struct ConsoleView {
  std::string study, participant, phase, current, next_placement;
  int done = 0, total = 0;  ///< rated trials of the main phases completed / planned
  int training_done = 0, training_total = 0;  ///< training trials (shown apart from the progress)
  std::vector<float> force_N, speed_mps, acc_mps2;  ///< recent samples, oldest first
  std::string device_status;
  std::map<std::string, std::uint64_t> faults;  ///< counter name -> count
  bool paused = false;
  bool on_break = false;  ///< a break is running (countdown below)
  double break_remaining_s = 0;
  bool confirm_abort = false;    ///< the abort confirmation is open (modal)
  std::vector<std::string> log;  ///< recent events, newest last
};

/// What the experimenter did this frame. `abort` only asks: the console then shows a modal
/// confirmation, and `abort_confirmed` / `abort_cancelled` answer it.
struct ConsoleAction {
  bool pause = false, resume = false, take_break = false, end_break = false, abort = false;
  bool abort_confirmed = false, abort_cancelled = false;
};

ConsoleAction DrawConsole(const ConsoleView& v, Drawn* drawn = nullptr);

}  // namespace hapticlab::runner::ui
