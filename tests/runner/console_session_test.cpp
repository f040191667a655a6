// The experimenter console through a whole real-vs-virtual session (runner/ui/src/
// session_ui.cpp, console.cpp; runner/src/session_queue.cpp) under Xvfb, with a scripted
// experimenter and a scripted rating box for the participant:
// - no trial with a real sample starts before the experimenter confirms its samples, and
//   each confirmation is logged as a 'samples-placed' event with the trial's plan number;
// - a break shows the NEXT trial and the count of trials rated so far;
// - the live traces carry their units, and their values are the recorded stream's values at
//   the same instant (read back from the database);
// - the consent modal names the protocol's document and version and takes only a code.
// Screenshots go to <build>/screenshots (docs/img holds copies).
// Built into runner_screenshot_test (tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/force_record.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/runner_ui/session_ui.hpp"
#include "hapticlab/test/test_util.hpp"
#include "screenshot_util.hpp"

namespace hapticlab::runner::ui::console_session_test {
namespace {

using test_screens::Bright;
using S = ConsoleView::State;

std::string Shots() {
  const std::string out = std::string(HL_BINARY_DIR) + "/screenshots";
  std::filesystem::create_directories(out);
  return out;
}

// The participant's rating box, fed by the test: reports queued, then "nothing new".
class QueuedBox : public devices::RatingInput {
 public:
  devices::RatingEvent Poll() override {
    if (q.empty()) return {};
    const auto e = q.front();
    q.pop_front();
    return e;
  }
  std::deque<devices::RatingEvent> q;
};

// The plan number the console names in "trial 17: ..." (or "training trial 3: ...").
int PlanNumber(const std::string& now) {
  static const std::regex re("trial ([0-9]+):");
  std::smatch m;
  return std::regex_search(now, m, re) ? std::stoi(m[1]) : -1;
}

struct Seen {
  std::map<int, int> placed_frames;     // plan number -> frames shown in kPlaceSamples
  std::set<int> confirmed;              // plan numbers whose samples were confirmed
  std::vector<std::string> violations;  // exploring before confirmation
  int rated = 0;                        // rated (non-training) trials, counted by the script
  bool break_checked = false, traces_checked = false, placed_shot = false;
  int break_next = -1, break_done = -1, rated_at_break = -1;
  // A console frame's traces, to compare with the stream.
  int trace_plan = -1, trace_side = -1;
  std::string trace_source;
  std::vector<Trace> traces;
};

TEST(Screenshot, RealVsVirtualSessionThroughTheConsole) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  QueuedBox box;
  WindowSessionUi ui(p.name, "P01", "sim (simulated rig)", {.width = 1000, .height = 760}, &box);
  Seen seen;
  S last = S::kStarting;
  int last_plan = -1;
  std::string rated_phase;
  bool box_next = false;  // alternate the confirmation: console button, then the rating box
  ui.SetConsoleScript([&](const ConsoleView& cv, const Drawn& d) {
    ConsoleAction a;
    if (cv.state == S::kConsent && Find(d, "consent-modal")) {  // where the runner asks for it
      a.consent_code = "E01";
      a.consent_confirmed = true;
      return a;
    }
    const int plan = PlanNumber(cv.now);
    if (cv.state == S::kExploring && plan > 0 &&
        cv.next_placement.find("real") != std::string::npos && !seen.confirmed.count(plan))
      seen.violations.push_back("trial " + std::to_string(plan) + " explored before placement");
    if (cv.state == S::kPlaceSamples && Find(d, "samples-placed")) {
      // Hold the placement a few frames: nothing may start meanwhile.
      if (++seen.placed_frames[plan] >= 4) {
        if (!seen.placed_shot) {
          ui.SaveScreenshot(1, Shots() + "/console-place-samples.png");
          const cv::Mat c = cv::imread(Shots() + "/console-place-samples.png");
          EXPECT_GT(Bright(c, *Find(d, "place")), 15) << "the placement is written out";
          EXPECT_GT(Bright(c, *Find(d, "samples-placed")), 15) << "the button has its text";
          seen.placed_shot = true;
        }
        seen.confirmed.insert(plan);
        if (box_next) {
          box.q.push_back({true, 0.5, false});
          box.q.push_back({true, 0.5, true});
        } else {
          a.samples_placed = true;
        }
        box_next = !box_next;
      }
    }
    if (cv.state == S::kRating && last != S::kRating) {
      // The participant: knob, press per criterion (a different position for each).
      for (std::size_t i = 0; i < p.criteria.size(); ++i) {
        const double pos = 0.2 + 0.3 * static_cast<double>(i);
        box.q.push_back({true, pos, false});
        box.q.push_back({true, pos, true});
        box.q.push_back({true, pos, false});
      }
    }
    // A rating ended (the next trial's screens follow at once).
    if (last == S::kRating && cv.state != S::kRating && rated_phase != "training") ++seen.rated;
    if (cv.state == S::kRating) rated_phase = cv.phase;
    if (cv.state == S::kBreak && Find(d, "state:break") && !seen.break_checked) {
      ui.SaveScreenshot(1, Shots() + "/console-break.png");
      seen.break_checked = true;
      seen.break_next = plan;
      seen.break_done = cv.done;
      seen.rated_at_break = seen.rated;
      a.end_break = true;
    }
    // Traces: the last frame of the first virtual side on which every trace has values (the
    // frames of that side are taken in turn; the last one is compared with the stream).
    const bool same_side = seen.trace_source.empty() || seen.trace_source == cv.trace_source;
    if (same_side && cv.state == S::kExploring &&
        cv.trace_source.find("virtual") != std::string::npos) {
      bool full = true;
      for (const auto& tr : cv.traces) full = full && tr.values.size() >= 2;
      if (full) {
        seen.traces_checked = true;
        seen.trace_source = cv.trace_source;
        seen.traces = cv.traces;
        seen.trace_plan = plan;
        seen.trace_side = cv.trace_source.find("side A") != std::string::npos ? 0 : 1;
        ui.SaveScreenshot(1, Shots() + "/console-exploring.png");
        const cv::Mat c = cv::imread(Shots() + "/console-exploring.png");
        for (const auto& tr : cv.traces)
          EXPECT_GT(Bright(c, *Find(d, "trace:" + tr.id)), 15) << tr.id;
        EXPECT_GT(Bright(c, *Find(d, "timing")), 15);
        EXPECT_GT(Bright(c, *Find(d, "link")), 15);
      }
    }
    if (cv.state == S::kExploring) last_plan = plan;
    last = cv.state;
    return a;
  });
  RunOptions o;
  o.db_path = dir.File("console.db");
  o.participant = "P01";
  o.ui = &ui;
  o.ui_playback_speed = 2;   // 0.5 s sides in 0.25 s: several frames each on a busy machine
  o.stop_after_trials = 14;  // training, the reference trials and a break into the main phase
  const auto sum = RunStudy(p, o);
  EXPECT_EQ(sum.executed, 14);
  EXPECT_TRUE(seen.violations.empty()) << seen.violations.front();
  EXPECT_GE(last_plan, 1);

  // Every started trial with a real sample was confirmed first, and the event says so with
  // its plan number.
  db::Database database(o.db_path);
  const auto trials = database.Trials(sum.session_id);
  const auto events = database.Events(sum.session_id);
  int real_started = 0;
  for (const auto& t : trials) {
    const bool real = t.left.rfind("real:", 0) == 0 || t.right.rfind("real:", 0) == 0;
    if (!real || t.attempts == 0) continue;
    ++real_started;
    const int number = t.plan_index + 1;
    EXPECT_TRUE(seen.confirmed.count(number)) << "trial " << number;
    EXPECT_GE(seen.placed_frames[number], 4) << "trial " << number << " waited for it";
    int logged = 0;
    for (const auto& e : events)
      if (e.kind == db::EventKind::kSamplesPlaced && e.trial_id == t.id) {
        ++logged;
        EXPECT_EQ(e.detail.rfind("trial " + std::to_string(number) + ": left = ", 0), 0u)
            << e.detail;
        EXPECT_NE(e.detail.find("confirmed by the experimenter"), std::string::npos);
      }
    EXPECT_EQ(logged, t.attempts) << "one confirmation per start of trial " << number;
  }
  EXPECT_GT(real_started, 3) << "the reference and main phases hold real samples";
  bool by_box = false, by_button = false;
  for (const auto& e : events) {
    by_box = by_box || e.detail.find("rating box button") != std::string::npos;
    by_button = by_button || e.detail.find("console button") != std::string::npos;
  }
  EXPECT_TRUE(by_box && by_button) << "both ways of confirming were used and logged";

  // The break showed the trial that followed it, and the rated count so far.
  ASSERT_TRUE(seen.break_checked) << "a planned break fell into the first 14 trials";
  const db::Event* brk = nullptr;
  for (const auto& e : events)
    if (e.kind == db::EventKind::kBreak) brk = &e;
  ASSERT_TRUE(brk && brk->trial_id);
  for (const auto& t : trials)
    if (t.id == *brk->trial_id) {
      EXPECT_EQ(seen.break_next, t.plan_index + 1);
    }
  EXPECT_EQ(seen.break_done, seen.rated_at_break) << "the console counts every rated trial";
  EXPECT_GT(seen.rated_at_break, 0);

  // The traces are the recorded stream at the same instant, in their units.
  ASSERT_TRUE(seen.traces_checked);
  const std::vector<std::string> labels = {"normal force [N]", "tangential force [N]",
                                           "tangential speed [m/s]", "vibration command [m/s^2]"};
  ASSERT_EQ(seen.traces.size(), labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) EXPECT_EQ(seen.traces[i].label, labels[i]);
  const db::Trial* traced = nullptr;
  for (const auto& t : trials)
    if (t.plan_index + 1 == seen.trace_plan) traced = &t;
  ASSERT_TRUE(traced);
  const std::string side = seen.trace_side == 0 ? "left" : "right";
  const auto row_at = [&](const std::string& stream, double t_s) -> std::vector<float> {
    for (const auto& c : database.TrajectoryChunks(traced->id)) {
      if (c.stream != stream) continue;
      const double k = std::round((t_s - c.start_time_s) * c.rate_hz);
      if (k < 0 || k >= static_cast<double>(c.sample_count())) continue;
      const auto n = c.channels.size();
      const auto at = static_cast<std::size_t>(k) * n;
      return {c.samples.begin() + static_cast<std::ptrdiff_t>(at),
              c.samples.begin() + static_cast<std::ptrdiff_t>(at + n)};
    }
    return {};
  };
  using db::Col;
  using db::ForceChannel;
  const auto force = row_at(side + "_force", seen.traces[0].t_s);
  ASSERT_EQ(force.size(), db::kForceChannelCount) << "the row the console showed is stored";
  EXPECT_EQ(seen.traces[0].values.back(), force[Col(ForceChannel::kNormal_N)]);
  EXPECT_EQ(seen.traces[1].values.back(),
            std::hypot(force[Col(ForceChannel::kFx_N)], force[Col(ForceChannel::kFy_N)]));
  EXPECT_EQ(seen.traces[2].values.back(), force[Col(ForceChannel::kSpeed_mps)]);
  EXPECT_GT(seen.traces[0].values.back() + seen.traces[2].values.back(), 0.f)
      << "a side in contact, moving";
  const auto vib = row_at(side + "_vibration", seen.traces[3].t_s);
  ASSERT_EQ(vib.size(), 1u);
  EXPECT_EQ(seen.traces[3].values.back(), vib[0]);
}

TEST(Screenshot, ConsentModalNamesTheDocumentAndTakesOnlyACode) {
  WindowSessionUi ui("s", "P07", "test", {.width = 900, .height = 650});
  int step = 0;
  std::string refused;
  ui.SetConsoleScript([&](const ConsoleView& cv, const Drawn& d) {
    ConsoleAction a;
    if (!Find(d, "consent-modal") || ++step < 3) return a;  // the popup shows from its 2nd frame
    if (step == 3) {  // a name is refused, with a digit too (the database's rule)
      a.consent_code = "Smith1";
      a.consent_confirmed = true;
    } else if (step == 6) {
      refused = cv.consent_error;
      EXPECT_TRUE(Find(d, "consent-error"));
    } else if (step == 8) {
      // (The code field keeps what was typed into it; a script's code goes with its confirm.)
      ui.SaveScreenshot(1, Shots() + "/console-consent.png");
      const cv::Mat c = cv::imread(Shots() + "/console-consent.png");
      EXPECT_GT(Bright(c, *Find(d, "consent-document")), 15);
      EXPECT_GT(Bright(c, *Find(d, "consent-confirm")), 15);
      EXPECT_EQ(cv.consent_document, "consent-form.pdf");
      EXPECT_EQ(cv.consent_version, "2026-03");
      a.consent_code = "E07";
      a.consent_confirmed = true;
    }
    return a;
  });
  const auto code = ui.ConfirmConsent(
      {.study = "s", .participant = "P07", .document = "consent-form.pdf", .version = "2026-03"});
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, "E07");
  EXPECT_NE(refused.find("'Smith1' is not an experimenter code"), std::string::npos) << refused;
  EXPECT_EQ(ui.console().state, S::kStarting) << "the console goes back to where it was";
}

}  // namespace
}  // namespace hapticlab::runner::ui::console_session_test
