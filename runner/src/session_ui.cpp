#include "hapticlab/runner/session_ui.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace hapticlab::runner::ui {

WindowSessionUi::WindowSessionUi(const std::string& study, const std::string& participant, const std::string& device_status,
                                 const WindowOptions& o, devices::RatingInput* box)
    : win_(o), box_(box) {
  cv_.study = study;
  cv_.participant = participant;
  cv_.device_status = device_status;
}

bool WindowSessionUi::Frame(ParticipantAction* pa) {
  for (;;) {
    ConsoleAction ca;
    ParticipantAction a;
    if (!win_.Frame(pv_, cv_, &a, &ca)) return false;  // a window was closed: abort
    if (pa) *pa = a;
    if (ca.abort) return false;
    if (ca.take_break) break_requested_ = true;
    if (ca.pause) cv_.paused = true;
    if (ca.resume) cv_.paused = false;
    std::this_thread::sleep_for(std::chrono::milliseconds(15));  // ~60 frames per second without vsync
    if (!cv_.paused) return true;
    const auto saved = pv_;
    pv_.mode = ParticipantView::Mode::kMessage;
    pv_.message = "Paused. Please wait for the experimenter.";
    ConsoleAction c2;
    while (cv_.paused) {
      if (!win_.Frame(pv_, cv_, nullptr, &c2) || c2.abort) return false;
      if (c2.resume) cv_.paused = false;
      std::this_thread::sleep_for(std::chrono::milliseconds(15));
    }
    pv_ = saved;
    return true;
  }
}

void WindowSessionUi::Show(const TrialScreen& t) {
  cv_.phase = t.phase;
  cv_.done = t.index - 1;
  cv_.total = t.total;
  cv_.current = fmt::format("trial {}: {} | {}{}", t.index, t.left, t.right, t.method.empty() ? "" : " (" + t.method + ")");
  cv_.next_placement = t.placement;
  pv_.trial = t.index;
  pv_.trials = t.total;
  pv_.criteria = t.criteria;
  pv_.scale_min = t.scale_min;
  pv_.scale_max = t.scale_max;
  pv_.scale_low = t.scale_low;
  pv_.scale_high = t.scale_high;
}

bool WindowSessionUi::Stimulus(const TrialScreen& t, int side, const Eigen::Vector3d& stylus_m, double remaining_s) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kStimulus;
  const Eigen::Vector2d centre = side == 0 ? pv_.left_square_m : pv_.right_square_m;
  pv_.stylus_m = Eigen::Vector3d(centre.x() + stylus_m.x(), centre.y() + stylus_m.y(), stylus_m.z());
  // Traces for the console: the stylus speed proxy and penetration-as-force proxy are what the
  // sim provides; real devices fill them from the force stream.
  cv_.speed_mps.push_back(static_cast<float>(stylus_m.head<2>().norm()));
  cv_.force_N.push_back(static_cast<float>(std::max(0.0, -stylus_m.z()) * 1000));
  if (cv_.speed_mps.size() > 300) cv_.speed_mps.erase(cv_.speed_mps.begin());
  if (cv_.force_N.size() > 300) cv_.force_N.erase(cv_.force_N.begin());
  cv_.current += fmt::format(" - exploring the {} sample, {:.1f} s left", side == 0 ? "left" : "right", remaining_s);
  return Frame();
}

std::optional<std::vector<double>> WindowSessionUi::Rate(const TrialScreen& t) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kRating;
  pv_.ratings.assign(t.criteria.size(), std::nullopt);  // no default position
  focus_ = 0;
  box_pos_ = -1;
  for (;;) {
    ParticipantAction a;
    if (!Frame(&a)) return std::nullopt;
    pv_.ratings = a.ratings;
    if (box_) {
      // The rating box: turning the knob sets the focused scale; a press moves the focus to
      // the next scale, and on the last one (every scale set) confirms.
      const auto e = box_->Poll();
      if (e.valid && !pv_.ratings.empty()) {
        const bool moved = box_pos_ < 0 || std::abs(e.position - box_pos_) > 0.005;
        const bool press = e.confirm && !box_button_;
        box_pos_ = e.position;
        box_button_ = e.confirm;
        if (moved) pv_.ratings[focus_] = t.scale_min + e.position * (t.scale_max - t.scale_min);
        const bool all = std::all_of(pv_.ratings.begin(), pv_.ratings.end(), [](const auto& x) { return x.has_value(); });
        if (press && pv_.ratings[focus_]) {
          if (focus_ + 1 < pv_.ratings.size()) ++focus_;
          else if (all) a.confirmed = true;
        }
      }
    }
    if (a.confirmed) {
      a.ratings = pv_.ratings;
      std::vector<double> r;
      for (const auto& x : a.ratings) r.push_back(*x);
      cv_.log.push_back(fmt::format("trial {} rated", t.index));
      return r;
    }
  }
}

std::optional<int> WindowSessionUi::Choose(const TrialScreen& t) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kChoice;
  pv_.question = t.question;
  pv_.answers = t.answers;
  pv_.highlighted = -1;
  if (t.answers.empty()) return std::nullopt;
  for (;;) {
    ParticipantAction a;
    if (!Frame(&a)) return std::nullopt;
    if (box_) {
      const auto e = box_->Poll();
      if (e.valid) {
        const bool press = e.confirm && !box_button_;
        box_button_ = e.confirm;
        const auto n = static_cast<int>(t.answers.size());
        pv_.highlighted = std::clamp(static_cast<int>(e.position * n), 0, n - 1);
        if (press) a.chosen = pv_.highlighted;
      }
    }
    if (a.chosen) {
      cv_.log.push_back(fmt::format("trial {}: answered {}", t.index, t.answers[static_cast<std::size_t>(*a.chosen)]));
      return a.chosen;
    }
  }
}

bool WindowSessionUi::Break(double seconds) {
  const auto saved = pv_;
  pv_.mode = ParticipantView::Mode::kBreak;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const double left = seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0) break;
    pv_.break_remaining_s = left;
    if (!Frame()) return false;
  }
  pv_ = saved;
  break_requested_ = false;
  return true;
}

void WindowSessionUi::Event(const std::string& line) {
  cv_.log.push_back(line);
  if (line.find("fault") != std::string::npos) ++cv_.faults["device faults"];
}

}  // namespace hapticlab::runner::ui
