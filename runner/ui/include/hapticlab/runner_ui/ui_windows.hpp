#pragma once
/// @file The participant window and the experimenter console as GLFW windows with OpenGL and
/// Dear ImGui (one ImGui context each, so they can sit on two monitors). Input is read from
/// GLFW directly each frame (mouse position and buttons), which keeps the two contexts apart.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/runner_ui/screens.hpp"

namespace hapticlab::runner::ui {

struct WindowOptions {
  int width = 1280, height = 800;       ///< of each window [px]
  bool participant_fullscreen = false;  ///< on the participant's monitor (the last one)
  bool visible = true;                  ///< false: off-screen (screenshots)
};

class Windows {
 public:
  /// @throws std::runtime_error when there is no display (set DISPLAY, or run under xvfb-run)
  explicit Windows(const WindowOptions& o = {});
  ~Windows();
  Windows(const Windows&) = delete;
  Windows& operator=(const Windows&) = delete;
  /// Draws one frame in each window and handles input; false once a window was closed.
  bool Frame(const ParticipantView& pv, const ConsoleView& cv, ParticipantAction* pa,
             ConsoleAction* ca, Drawn* participant_drawn = nullptr, Drawn* console_drawn = nullptr);
  /// Clears the windows' close requests (the close button asks for a confirmation first).
  void KeepOpen();
  /// Writes the last frame of window 0 (participant) or 1 (console) as PNG.
  void SaveScreenshot(int window, const std::string& path) const;

 private:
  struct Win;
  std::vector<std::unique_ptr<Win>> wins_;
};

}  // namespace hapticlab::runner::ui
