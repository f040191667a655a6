#include "hapticlab/runner_ui/session_ui.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace hapticlab::runner::ui {

WindowSessionUi::WindowSessionUi(const std::string& study, const std::string& participant,
                                 const std::string& device_status, const WindowOptions& o,
                                 devices::RatingInput* box)
    : win_(o), box_(box) {
  cv_.study = study;
  cv_.participant = participant;
  cv_.device_status = device_status;
}

void WindowSessionUi::Log(const std::string& kind, const std::string& detail) {
  cv_.log.push_back(detail.empty() ? kind : kind + ": " + detail);
  if (log_event) log_event(kind, detail);
}

bool WindowSessionUi::Frame(ParticipantAction* pa) {
  const ParticipantView saved = pv_;
  bool held = false;  // paused or asked to confirm an abort: the participant waits
  for (bool first = true;; first = false) {
    ConsoleAction ca;
    ParticipantAction a;
    Drawn drawn;
    const bool open = win_.Frame(pv_, cv_, held ? nullptr : &a, &ca, nullptr, &drawn);
    if (first && pa) *pa = a;
    if (script_) {
      const ConsoleAction s = script_(cv_, drawn);
      ca.pause |= s.pause;
      ca.resume |= s.resume;
      ca.take_break |= s.take_break;
      ca.end_break |= s.end_break;
      ca.abort |= s.abort;
      ca.abort_confirmed |= s.abort_confirmed;
      ca.abort_cancelled |= s.abort_cancelled;
    }
    if (!open) {  // a window's close button: asks like Abort
      win_.KeepOpen();
      ca.abort = true;
    }
    if (cv_.confirm_abort) {
      if (ca.abort_confirmed) {
        Log("abort-confirmed", cv_.current);
        return false;
      }
      if (ca.abort_cancelled) {
        cv_.confirm_abort = false;
        Log("abort-cancelled", "the session continues");
      }
    } else if (ca.abort) {
      cv_.confirm_abort = true;
      Log("abort-requested", cv_.current);
    }
    if (ca.take_break && !cv_.on_break && !break_requested_) {
      break_requested_ = true;
      Log("break-requested", "the break starts before the next trial");
    }
    if (ca.end_break && cv_.on_break) end_break_ = true;
    if (ca.pause && !cv_.paused) {
      cv_.paused = true;
      Log("pause", cv_.current);
    }
    if (ca.resume && cv_.paused) {
      cv_.paused = false;
      Log("resume", cv_.current);
    }
    std::this_thread::sleep_for(
        std::chrono::milliseconds(15));  // ~60 frames per second without vsync
    if (!cv_.paused && !cv_.confirm_abort) {
      if (held) pv_ = saved;
      return true;
    }
    if (!held) {
      held = true;
      pv_.mode = ParticipantView::Mode::kMessage;
      pv_.message = "Paused. Please wait for the experimenter.";
    }
  }
}

void WindowSessionUi::Show(const TrialScreen& t) {
  cv_.phase = t.phase;
  cv_.done = t.rated_total > 0 ? t.rated_done : t.index - 1;
  cv_.total = t.rated_total > 0 ? t.rated_total : t.total;
  cv_.training_done = t.training_done;
  cv_.training_total = t.training_total;
  cv_.current = fmt::format("{} {}: {} | {}{}", t.training ? "training trial" : "trial", t.index,
                            t.left, t.right, t.method.empty() ? "" : " (" + t.method + ")");
  cv_.next_placement = t.placement;
  pv_.trial = t.index;
  pv_.trials = t.total;
  pv_.training = t.training;
  // The participant's prompt per phase (the same for reference and main trials: the
  // participant is not told which sample is real).
  pv_.stimulus_prompt = t.training ? "Training (not rated): explore A and B with the stylus"
                        : !t.answers.empty()
                            ? "Explore each interval, then answer"
                            : "Explore A, then B: you will rate how similar they feel";
  pv_.criteria = t.criteria;
  pv_.scale_min = t.scale_min;
  pv_.scale_max = t.scale_max;
  pv_.scale_low = t.scale_low;
  pv_.scale_high = t.scale_high;
}

bool WindowSessionUi::Stimulus(const TrialScreen& t, int side, const Eigen::Vector3d& stylus_m,
                               double remaining_s) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kStimulus;
  const Eigen::Vector2d centre = side == 0 ? pv_.left_square_m : pv_.right_square_m;
  pv_.stylus_m =
      Eigen::Vector3d(centre.x() + stylus_m.x(), centre.y() + stylus_m.y(), stylus_m.z());
  // Traces for the console: the stylus speed proxy and penetration-as-force proxy are what the
  // sim provides; real devices fill them from the force stream.
  cv_.speed_mps.push_back(static_cast<float>(stylus_m.head<2>().norm()));
  cv_.force_N.push_back(static_cast<float>(std::max(0.0, -stylus_m.z()) * 1000));
  if (cv_.speed_mps.size() > 300) cv_.speed_mps.erase(cv_.speed_mps.begin());
  if (cv_.force_N.size() > 300) cv_.force_N.erase(cv_.force_N.begin());
  cv_.current += fmt::format(" - exploring {}, {:.1f} s left", side == 0 ? "A (left)" : "B (right)",
                             remaining_s);
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
        const bool all = std::all_of(pv_.ratings.begin(), pv_.ratings.end(),
                                     [](const auto& x) { return x.has_value(); });
        if (press && pv_.ratings[focus_]) {
          if (focus_ + 1 < pv_.ratings.size())
            ++focus_;
          else if (all)
            a.confirmed = true;
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
      cv_.log.push_back(fmt::format("trial {}: answered {}", t.index,
                                    t.answers[static_cast<std::size_t>(*a.chosen)]));
      return a.chosen;
    }
  }
}

bool WindowSessionUi::Break(double seconds) {
  const auto saved = pv_;
  pv_.mode = ParticipantView::Mode::kBreak;
  cv_.on_break = true;
  end_break_ = false;
  const auto t0 = std::chrono::steady_clock::now();
  bool go_on = true;
  for (;;) {
    const double left =
        seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0) break;
    pv_.break_remaining_s = cv_.break_remaining_s = left;
    if (!Frame()) {
      go_on = false;
      break;
    }
    if (end_break_) {
      Log("break-ended", fmt::format("the experimenter ended the break with {:.0f} s left", left));
      break;
    }
  }
  cv_.on_break = false;
  end_break_ = false;
  pv_ = saved;
  break_requested_ = false;
  return go_on;
}

void WindowSessionUi::Event(const std::string& line) {
  cv_.log.push_back(line);
  if (line.find("fault") != std::string::npos) ++cv_.faults["device faults"];
}

}  // namespace hapticlab::runner::ui
