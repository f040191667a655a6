#include "hapticlab/runner_ui/session_ui.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <thread>
#include <utility>

#include "hapticlab/core/participant_code.hpp"

namespace hapticlab::runner::ui {

WindowSessionUi::WindowSessionUi(const std::string& study, const std::string& participant,
                                 const std::string& device_status, const WindowOptions& o,
                                 devices::RatingInput* box)
    : win_(o), box_(box) {
  cv_.study = study;
  cv_.participant = participant;
  cv_.device_status = device_status;
  cv_.trace_source = "no side has run yet";
  for (const auto& [id, label] : {std::pair{"normal", "normal force [N]"},
                                  {"tangential", "tangential force [N]"},
                                  {"speed", "tangential speed [m/s]"},
                                  {"vibration", "vibration command [m/s^2]"}})
    cv_.traces.push_back({.id = id, .label = label, .values = {}, .t_s = 0, .none = "no data yet"});
}

void WindowSessionUi::Log(db::EventKind kind, const std::string& detail) {
  const std::string name(NameOf(db::kEventKindNames, kind));
  cv_.log.push_back(detail.empty() ? name : name + ": " + detail);
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
      ca.samples_placed |= s.samples_placed;
      ca.samples_placed_by_key |= s.samples_placed_by_key;
      if (s.consent_code) ca.consent_code = s.consent_code;
      ca.consent_confirmed |= s.consent_confirmed;
    }
    if (ca.consent_code) cv_.consent_code = *ca.consent_code;
    if (ca.consent_confirmed && cv_.state == ConsoleView::State::kConsent) consent_confirm_ = true;
    if (ca.samples_placed && cv_.state == ConsoleView::State::kPlaceSamples && !cv_.paused) {
      placed_ = true;
      placed_by_key_ = ca.samples_placed_by_key;
    }
    UpdateTimes();
    if (!open) {  // a window's close button: asks like Abort
      win_.KeepOpen();
      ca.abort = true;
    }
    if (cv_.confirm_abort) {
      if (ca.abort_confirmed) {
        Log(db::EventKind::kAbortConfirmed, cv_.now);
        return false;
      }
      if (ca.abort_cancelled) {
        cv_.confirm_abort = false;
        Log(db::EventKind::kAbortCancelled, "the session continues");
      }
    } else if (ca.abort) {
      cv_.confirm_abort = true;
      Log(db::EventKind::kAbortRequested, cv_.now);
    }
    const bool on_break = cv_.state == ConsoleView::State::kBreak;
    if (ca.take_break && !on_break && !break_requested_) {
      break_requested_ = true;
      Log(db::EventKind::kBreakRequested, "the break starts before the next trial");
    }
    if (ca.end_break && on_break) end_break_ = true;
    if (ca.pause && !cv_.paused) {
      cv_.paused = true;
      Log(db::EventKind::kPause, cv_.now);
    }
    if (ca.resume && cv_.paused) {
      cv_.paused = false;
      Log(db::EventKind::kResume, cv_.now);
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

namespace {

// "trial 17: real Denim | virtual Denim (Hybrid)": the plan's 1-based number, as everywhere.
std::string Describe(const TrialScreen& t) {
  return fmt::format("{} {}: {}{}{}{}", t.training ? "training trial" : "trial", t.plan_number,
                     t.left, t.right.empty() ? "" : " | ", t.right,
                     t.method.empty() ? "" : " (" + t.method + ")");
}

}  // namespace

void WindowSessionUi::Show(const TrialScreen& t) {
  cv_.phase = t.phase;
  cv_.done = t.rated_total > 0 ? t.rated_done : t.index - 1;
  cv_.total = t.rated_total > 0 ? t.rated_total : t.total;
  cv_.training_done = t.training_done;
  cv_.training_total = t.training_total;
  cv_.now = Describe(t);
  cv_.next_placement = t.placement;
  pv_.trial = t.index;
  pv_.trials = t.total;
  pv_.training = t.training;
  pv_.right_present = !t.right.empty() || !t.answers.empty();
  // The participant's prompt per phase (the same for reference and main trials: the
  // participant is not told which sample is real); training names only the sides it uses.
  pv_.stimulus_prompt =
      t.training ? (pv_.right_present ? "Training (not rated): explore A and B with the stylus"
                                      : "Training (not rated): explore A with the stylus")
      : !t.answers.empty() ? "Explore each interval, then answer"
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
  cv_.state = ConsoleView::State::kExploring;
  cv_.now += fmt::format(" - exploring {}, {:.1f} s left", side == 0 ? "A (left)" : "B (right)",
                         remaining_s);
  return Frame();
}

std::optional<std::vector<double>> WindowSessionUi::Rate(const TrialScreen& t) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kRating;
  cv_.state = ConsoleView::State::kRating;
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
      cv_.log.push_back(fmt::format("trial {} rated", t.plan_number));
      cv_.state = ConsoleView::State::kNext;  // Upcoming names the next trial
      return r;
    }
  }
}

std::optional<int> WindowSessionUi::Choose(const TrialScreen& t) {
  Show(t);
  pv_.mode = ParticipantView::Mode::kChoice;
  cv_.state = ConsoleView::State::kRating;
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
      cv_.state = ConsoleView::State::kNext;
      cv_.log.push_back(fmt::format("trial {}: answered {}", t.plan_number,
                                    t.answers[static_cast<std::size_t>(*a.chosen)]));
      return a.chosen;
    }
  }
}

bool WindowSessionUi::Break(double seconds) {
  const auto saved = pv_;
  pv_.mode = ParticipantView::Mode::kBreak;
  const auto state = cv_.state;
  cv_.state = ConsoleView::State::kBreak;
  end_break_ = false;
  const auto t0 = std::chrono::steady_clock::now();
  bool go_on = true;
  for (;;) {
    const double left =
        seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0) break;
    pv_.break_remaining_s = cv_.break_remaining_s = left;
    if (StopRequested() || !Frame()) {  // a signal ends the break as the runner records it
      go_on = false;
      break;
    }
    if (end_break_) {
      Log(db::EventKind::kBreakEnded,
          fmt::format("the experimenter ended the break with {:.0f} s left", left));
      break;
    }
  }
  cv_.state = state;
  break_s_since_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  end_break_ = false;
  pv_ = saved;
  break_requested_ = false;
  return go_on;
}

void WindowSessionUi::Event(const std::string& line) {
  cv_.log.push_back(line);
  if (line.find("fault") != std::string::npos) ++cv_.faults["device faults"];
}

void WindowSessionUi::Live(const LiveFrame& f) {
  using db::Col;
  using db::ForceChannel;
  constexpr std::size_t kKeep = 300;  // samples per trace (5 s at the console's frame rate)
  const bool real = f.stimulus.rfind("real:", 0) == 0;
  if (live_closed_ || f.plan_number != live_plan_ || f.side != live_side_) {
    // A new side: its own traces, named with where they come from.
    live_plan_ = f.plan_number;
    live_side_ = f.side;
    live_closed_ = false;
    live_force_t_ = live_vib_t_ = -1;
    for (auto& tr : cv_.traces) tr.values.clear();
    cv_.trace_source = fmt::format(
        "trial {}, side {} ({}){}", f.plan_number, f.side == 0 ? "A (left)" : "B (right)",
        f.stimulus,
        real ? "; real sample: forces are the model's estimate from the stylus position, "
               "nothing is commanded"
             : "");
  }
  auto push = [&](Trace& tr, float x, double t_s) {
    tr.values.push_back(x);
    if (tr.values.size() > kKeep) tr.values.erase(tr.values.begin());
    tr.t_s = t_s;
  };
  if (f.force_recorded && f.force_t_s > live_force_t_) {
    live_force_t_ = f.force_t_s;
    const auto& r = f.force;
    push(cv_.traces[0], r[Col(ForceChannel::kNormal_N)], f.force_t_s);
    push(cv_.traces[1], std::hypot(r[Col(ForceChannel::kFx_N)], r[Col(ForceChannel::kFy_N)]),
         f.force_t_s);
    push(cv_.traces[2], r[Col(ForceChannel::kSpeed_mps)], f.force_t_s);
  }
  if (f.vibration_recorded && f.vibration_t_s > live_vib_t_) {
    live_vib_t_ = f.vibration_t_s;
    push(cv_.traces[3], f.vibration_mps2, f.vibration_t_s);
  }
  for (std::size_t i = 0; i < 3; ++i)
    cv_.traces[i].none = "no recorded row yet (none with --record none)";
  cv_.traces[3].none = real ? "none: a real sample does not vibrate"
                            : "none: no vibration stream (vibration off, no actuator, or "
                              "--record none / force)";
  // Health: the side's counters on top of the sides that ended.
  const EngineStats& e = f.engine;
  Health h = closed_;
  h.valid = true;
  h.virtual_clock = e.virtual_clock;
  h.late_p50_us = e.force_timing.late_p50_s * 1e6;
  h.late_p99_us = e.force_timing.late_p99_s * 1e6;
  h.misses_trial += e.force_deadline_misses;
  h.misses_session += e.force_deadline_misses;
  h.vib_misses_trial += e.vibration_deadline_misses;
  h.vib_misses_session += e.vibration_deadline_misses;
  h.lost_reads += e.lost_reads;
  h.empty_reads += e.empty_reads;
  h.disconnects += e.disconnects;
  h.stale += e.stale_faults;
  h.nan += e.nan_faults;
  h.overflows += e.recording_overflows;
  cv_.health = h;
  if (f.final) {
    closed_ = h;
    live_closed_ = true;
  }
}

void WindowSessionUi::Upcoming(const TrialScreen& next) {
  const auto now = std::chrono::steady_clock::now();
  if (last_upcoming_) {  // the previous trial's wall time, breaks excluded
    trial_s_sum_ += std::chrono::duration<double>(now - *last_upcoming_).count() - break_s_since_;
    ++trials_timed_;
  }
  last_upcoming_ = now;
  break_s_since_ = 0;
  next_ = next;
  Show(next);
  cv_.state = ConsoleView::State::kNext;
  closed_.misses_trial = closed_.vib_misses_trial = 0;
  cv_.health.misses_trial = cv_.health.vib_misses_trial = 0;
  UpdateTimes();
}

void WindowSessionUi::UpdateTimes() {
  const auto now = std::chrono::steady_clock::now();
  cv_.elapsed_s = std::chrono::duration<double>(now - opened_).count();
  if (!last_upcoming_) return;
  // The plan's rest: the trials not yet completed (the next one included) at the measured
  // mean wall time per trial (before any, the stimulus time plus 10 s to rate and place),
  // and the planned breaks ahead; minus the time the next trial has already taken.
  const int left =
      (next_.rated_total - next_.rated_done) + (next_.training_total - next_.training_done);
  const bool measured = trials_timed_ > 0;
  const double per_trial_s =
      measured ? trial_s_sum_ / trials_timed_ : next_.sides * next_.stimulus_s + 10.0;
  const double into_s =
      std::chrono::duration<double>(now - *last_upcoming_).count() - break_s_since_;
  // A break before the next trial: its remaining time while it runs, else all of it.
  const bool on_break = cv_.state == ConsoleView::State::kBreak;
  const double break_ahead_s = on_break                                    ? cv_.break_remaining_s
                               : next_.break_before && break_s_since_ == 0 ? next_.break_s
                                                                           : 0.0;
  cv_.eta_s = std::max(0.0, left * per_trial_s + next_.breaks_left * next_.break_s + break_ahead_s -
                                std::min(into_s, per_trial_s));
  const int breaks = next_.breaks_left + (break_ahead_s > 0 ? 1 : 0);
  cv_.eta_basis =
      fmt::format("{} trials at {:.{}f} s each ({}), {} planned break{} of {:.0f} s", left,
                  per_trial_s, per_trial_s < 10 ? 1 : 0, measured ? "measured" : "from the plan",
                  breaks, breaks == 1 ? "" : "s", next_.break_s);
}

bool WindowSessionUi::BoxPressed() {
  if (!box_) return false;
  const auto e = box_->Poll();
  if (!e.valid) return false;
  const bool press = e.confirm && !box_button_;
  box_button_ = e.confirm;
  return press;
}

std::optional<std::string> WindowSessionUi::ConfirmPlacement(const TrialScreen& t) {
  Show(t);
  cv_.state = ConsoleView::State::kPlaceSamples;
  const auto saved = pv_;
  pv_.mode = ParticipantView::Mode::kMessage;
  pv_.message = "Please wait: the experimenter is preparing the samples.";
  placed_ = placed_by_key_ = false;
  std::optional<std::string> how;
  for (;;) {
    // Ctrl-C or SIGTERM ends the wait: the runner records the signal (a trial boundary).
    if (StopRequested() || !Frame()) break;
    const bool box = BoxPressed();
    if (placed_ || box) {
      how = fmt::format("confirmed by the experimenter: {}", box              ? "rating box button"
                                                             : placed_by_key_ ? "console key"
                                                                              : "console button");
      break;
    }
  }
  pv_ = saved;
  cv_.state = ConsoleView::State::kNext;
  placed_ = false;
  if (how)
    cv_.log.push_back(fmt::format("trial {}: samples placed ({})", t.plan_number, t.placement));
  return how;
}

std::optional<std::string> WindowSessionUi::ConfirmConsent(const ConsentRequest& r) {
  const auto state = cv_.state;
  cv_.state = ConsoleView::State::kConsent;
  if (!r.participant.empty()) cv_.participant = r.participant;
  cv_.consent_document = r.document;
  cv_.consent_version = r.version;
  cv_.consent_code.clear();
  cv_.consent_error.clear();
  const auto saved = pv_;
  pv_.mode = ParticipantView::Mode::kMessage;
  pv_.message = "Welcome. The experimenter will start the study shortly.";
  consent_confirm_ = false;
  std::optional<std::string> code;
  for (;;) {
    if (StopRequested() || !Frame()) break;  // Ctrl-C or SIGTERM: the runner says so
    if (!consent_confirm_) continue;
    consent_confirm_ = false;
    const std::string& c = cv_.consent_code;
    // The database's rule for every pseudonymous code (the runner records the code only if it
    // passes it), so the console never accepts a code the session then refuses.
    const std::string why = PseudonymousCodeProblem(c);
    if (why.empty()) {
      code = c;
      break;
    }
    cv_.consent_error =
        fmt::format("'{}' is not an experimenter code ({}): expected a code such as E07 ({})", c,
                    why, kPseudonymousCodeRule);
  }
  pv_ = saved;
  cv_.state = state;
  if (code) cv_.log.push_back(fmt::format("consent confirmed by experimenter {}", *code));
  return code;
}

}  // namespace hapticlab::runner::ui
