#pragma once
/// @file The study's screens, drawn with Dear ImGui (dissertation ch. IV.5.1, V.2.1): the
/// participant window (two white squares where the real and the virtual sample lie, a sphere
/// cursor at the stylus, rating scales with no default position, a confirm button, the break
/// screen) and the experimenter console (the session's state, progress and time to the end,
/// the trial under way or next and the samples to place, live traces of the recorded streams
/// with their units, timing and link health, pause/break/abort, the consent and abort modals,
/// device status and fault counters). The draw functions only need an ImGui frame, so tests run
/// them headless; the windows (GLFW + OpenGL) are in ui_windows.hpp.

#include <Eigen/Core>
#include <cstdint>
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
  bool right_present = true;  ///< false: only A holds a sample (training), B is not drawn
};

struct ParticipantAction {
  std::vector<std::optional<double>> ratings;  ///< after this frame's input
  bool confirmed = false;                      ///< confirm pressed with every criterion rated
  std::optional<int> chosen;                   ///< choice mode: the answer clicked or keyed
};

/// Draws the participant window into the current ImGui frame (full window).
ParticipantAction DrawParticipant(const ParticipantView& v, Drawn* drawn = nullptr);

/// One live trace of the console: the newest values of one channel of the recorded streams.
struct Trace {
  std::string id;             ///< "normal", "tangential", "speed", "vibration"
  std::string label;          ///< with its unit, e.g. "normal force [N]"
  std::vector<float> values;  ///< recent samples of the side under way, oldest first
  double t_s = 0;             ///< time stamp of the newest value on the side's clock [s]
  std::string none;           ///< why there are no values (e.g. "not recorded (--record none)")
};

/// Timing and link health of the engine, as its counters and histograms stand.
struct Health {
  bool valid = false;                                  ///< false before the first side
  bool virtual_clock = false;                          ///< simulated: lateness is not measured
  double late_p50_us = 0, late_p99_us = 0;             ///< force loop, the side under way
  std::uint64_t misses_trial = 0, misses_session = 0;  ///< force-loop deadline misses
  std::uint64_t vib_misses_trial = 0, vib_misses_session = 0;  ///< vibration loop
  std::uint64_t lost_reads = 0, empty_reads = 0, disconnects = 0, stale = 0, nan = 0,
                overflows = 0;  ///< device link and recording counters, this session
};

struct ConsoleView {
  /// What the session is doing (the banner); `paused` shows over any of them.
  enum class State { kStarting, kConsent, kPlaceSamples, kExploring, kRating, kNext, kBreak };
  State state = State::kStarting;
  std::string study, participant, phase;
  std::string now;             ///< the trial under way, or the next one (kNext, kBreak, ...)
  std::string next_placement;  ///< what lies where in that trial
  int done = 0, total = 0;     ///< rated trials of the main phases completed / planned
  int training_done = 0, training_total = 0;  ///< training trials (shown apart from the progress)
  std::vector<Trace> traces;                  ///< normal, tangential, speed, vibration
  std::string trace_source;                   ///< which side and stream the traces show
  Health health;
  double elapsed_s = 0;   ///< since the console opened
  double eta_s = -1;      ///< estimated time to the end of the plan; < 0: unknown
  std::string eta_basis;  ///< what the estimate assumes
  std::string device_status;
  std::map<std::string, std::uint64_t> faults;  ///< counter name -> count
  bool paused = false;
  double break_remaining_s = 0;
  bool confirm_abort = false;  ///< the abort confirmation is open (modal)
  // The consent modal (State::kConsent): the protocol's document and version, the
  // experimenter code typed so far and why the last one was refused.
  std::string consent_document, consent_version, consent_code, consent_error;
  std::vector<std::string> log;  ///< recent events, newest last
};

/// What the experimenter did this frame. `abort` only asks: the console then shows a modal
/// confirmation, and `abort_confirmed` / `abort_cancelled` answer it.
struct ConsoleAction {
  bool pause = false, resume = false, take_break = false, end_break = false, abort = false;
  bool abort_confirmed = false, abort_cancelled = false;
  /// kPlaceSamples: "Samples placed" clicked (or Enter / Space pressed on the console).
  bool samples_placed = false;
  bool samples_placed_by_key = false;
  /// kConsent: the code field's text after this frame, and "Confirm consent" (or Enter).
  std::optional<std::string> consent_code;
  bool consent_confirmed = false;
};

/// The experimenter console (runner/ui/src/console.cpp).
ConsoleAction DrawConsole(const ConsoleView& v, Drawn* drawn = nullptr);

}  // namespace hapticlab::runner::ui
