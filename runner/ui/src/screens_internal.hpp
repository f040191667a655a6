#pragma once
// Drawing helpers shared by the participant window (screens.cpp) and the console
// (console.cpp); private to runner_ui.

#include <imgui.h>

#include <optional>
#include <string>

#include "hapticlab/runner_ui/screens.hpp"

namespace hapticlab::runner::ui::internal {

// Notes what was drawn where (for tests and screenshot checks).
void Record(Drawn* d, const std::string& id, ImVec2 a, ImVec2 b);
// Begins a borderless window covering the whole display.
void FullWindow(const char* name, ImU32 bg);
// A rating scale with no default position (the handle appears once a value is set).
bool RatingScale(const std::string& id, std::optional<double>* value, double lo, double hi,
                 float width, Drawn* drawn);
// Text at the cursor, recorded under `id`.
void TextRecorded(Drawn* d, const std::string& id, const std::string& text);

}  // namespace hapticlab::runner::ui::internal
