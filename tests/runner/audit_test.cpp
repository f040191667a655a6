// The audit trail (runner/audit.hpp): consent recorded only as it happened, every event naming
// who or what established it, faulted attempts counted, ratings stored as scale values.

#include "hapticlab/runner/audit.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <optional>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"
#include "study_checks.hpp"

namespace hapticlab::runner::audit_test {
namespace {

using test_checks::SmallProtocol;

// A participant window scripted to rate every trial with `scores` (float positions, as a
// mouse on the scale gives them) and, when `console_code` is set, a console that confirms
// consent with it.
class ScriptedUi final : public SessionUi {
 public:
  std::vector<double> scores{static_cast<double>(0.8f) * 100, static_cast<double>(0.37f) * 100};
  std::optional<std::string> console_code;
  bool abort_placement = false;      // the experimenter aborts at the first PLACE SAMPLES
  bool signal_at_placement = false;  // Ctrl-C arrives while PLACE SAMPLES waits
  std::vector<ConsentRequest> asked;
  bool Stimulus(const TrialScreen&, int, const Eigen::Vector3d&, double) override { return true; }
  std::optional<std::vector<double>> Rate(const TrialScreen&) override { return scores; }
  bool Break(double) override { return true; }
  std::optional<std::string> ConfirmConsent(const ConsentRequest& r) override {
    asked.push_back(r);
    if (signal_at_consent) RequestStop(SIGTERM);  // the console's wait then ends
    return console_code;
  }
  bool signal_at_consent = false;  // SIGTERM arrives while the consent modal waits
  std::optional<std::string> ConfirmPlacement(const TrialScreen& t) override {
    if (signal_at_placement) RequestStop(SIGINT);  // the window's wait then ends
    if (abort_placement || signal_at_placement) return std::nullopt;
    return SessionUi::ConfirmPlacement(t);
  }
};

// The field the first diagnostic of an InputError names.
template <class F>
std::string RefusedField(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.diagnostics().empty() ? "(none)" : e.diagnostics()[0].field;
  }
  return "(not refused)";
}

std::vector<db::Event> EventsOf(const std::string& path, const std::string& code) {
  db::Database d(path, {.create = false, .read_only = true});
  for (const auto& st : d.Studies())
    if (const auto p = d.FindParticipant(st.id, code)) return d.Events(d.Sessions(p->id).at(0).id);
  return {};
}

RunOptions PersonRun(const std::string& db, const std::string& code, SessionUi* ui) {
  RunOptions o;
  o.db_path = db;
  o.participant = code;
  o.record = RecordMode::kNone;
  o.ui = ui;
  o.ui_playback_speed = 1e6;
  o.stop_after_trials = 6;  // the 4 training trials and 2 rated ones
  return o;
}

TEST(Audit, ASimulatedSessionRecordsConsentAsNotApplicableAndNothingSigned) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  RunOptions o;
  o.db_path = dir.File("s.db");
  o.participant = "P01";
  o.record = RecordMode::kNone;
  ASSERT_EQ(RunStudy(p, o).status, db::SessionStatus::kCompleted);
  const auto events = EventsOf(o.db_path, "P01");
  int consent = 0;
  for (const auto& e : events) {
    EXPECT_EQ(e.detail.find("signed"), std::string::npos)
        << NameOf(db::kEventKindNames, e.kind) << ": " << e.detail;
    EXPECT_FALSE(e.established_by.empty()) << NameOf(db::kEventKindNames, e.kind);
    EXPECT_EQ(e.established_by.find("unrecorded"), std::string::npos)
        << NameOf(db::kEventKindNames, e.kind);
    if (e.kind != db::EventKind::kConsent) continue;
    ++consent;
    EXPECT_EQ(e.detail.rfind("not applicable: simulated", 0), 0u) << e.detail;
    EXPECT_EQ(e.established_by, source::kSessionMode);
  }
  EXPECT_EQ(consent, 1);
  // A consent code for a session no person takes part in is refused, before anything.
  o.participant = "P02";
  o.consent_confirmed_by = "E01";
  EXPECT_EQ(RefusedField([&] { RunStudy(p, o); }), "consent_confirmed_by");
  EXPECT_TRUE(EventsOf(o.db_path, "P02").empty());
}

TEST(Audit, APersonSessionNeedsAnExperimenterCodeAndRecordsItWithTheDocumentVersion) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;  // a console that cannot ask (console_code unset)
  auto o = PersonRun(dir.File("s.db"), "P03", &ui);
  EXPECT_EQ(RefusedField([&] { RunStudy(p, o); }), "consent_confirmed_by");
  {
    db::Database d(o.db_path, {.create = false, .read_only = true});
    for (const auto& st : d.Studies()) EXPECT_TRUE(d.Participants(st.id).empty());
  }
  o.consent_confirmed_by = "Alice";  // a name, not a code
  EXPECT_EQ(RefusedField([&] { RunStudy(p, o); }), "consent_confirmed_by");
  EXPECT_EQ(ui.asked.size(), 1u) << "without a code the console is asked (and cannot)";
  ui.asked.clear();
  o.consent_confirmed_by = "E01";
  EXPECT_EQ(RunStudy(p, o).status, db::SessionStatus::kAborted);  // stopped after 6 trials
  int consent = 0;
  for (const auto& e : EventsOf(o.db_path, "P03")) {
    if (e.kind != db::EventKind::kConsent) continue;
    ++consent;
    EXPECT_EQ(e.established_by, "experimenter:E01");
    EXPECT_NE(e.detail.find("E01"), std::string::npos) << e.detail;
    EXPECT_NE(e.detail.find("\"test-small consent form\""), std::string::npos) << e.detail;
    EXPECT_NE(e.detail.find("version \"2026-11\""), std::string::npos) << e.detail;
    EXPECT_NE(e.detail.find("command line"), std::string::npos) << e.detail;
  }
  EXPECT_EQ(consent, 1);
  EXPECT_TRUE(ui.asked.empty()) << "confirmed on the command line: the console does not ask";
  // A protocol without [consent] cannot run with a person.
  auto text = test::ReadFile(SmallProtocol());
  text = text.substr(0, text.find("[consent]"));
  const auto bare = protocols::ParseProtocol(text, SmallProtocol());
  o.participant = "P04";
  EXPECT_EQ(RefusedField([&] { RunStudy(bare, o); }), "consent");
}

TEST(Audit, AConsoleConfirmationIsRecordedThroughTheSameRecord) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  ui.console_code = "E07";
  const auto o = PersonRun(dir.File("s.db"), "P05", &ui);
  RunStudy(p, o);
  ASSERT_EQ(ui.asked.size(), 1u);
  EXPECT_EQ(ui.asked[0].document, "test-small consent form");
  EXPECT_EQ(ui.asked[0].version, "2026-11");
  EXPECT_EQ(ui.asked[0].participant, "P05");
  bool found = false;
  for (const auto& e : EventsOf(o.db_path, "P05"))
    found |= e.kind == db::EventKind::kConsent && e.established_by == "experimenter:E07" &&
             e.detail.find("(console)") != std::string::npos;
  EXPECT_TRUE(found);
  // Not confirmed in the console: refused, nothing of the participant written.
  ui.console_code.reset();
  auto again = o;
  again.participant = "P06";
  EXPECT_EQ(RefusedField([&] { RunStudy(p, again); }), "consent_confirmed_by");
  EXPECT_TRUE(EventsOf(o.db_path, "P06").empty());
  // The API directly: a record with a name is refused.
  db::Database d(o.db_path);
  const auto session = d.Sessions(d.FindParticipant(d.Studies()[0].id, "P05")->id).at(0).id;
  EXPECT_THROW(RecordConsent(d, session, {"Bob", "doc", "1", "console"}), InputError);
  EXPECT_THROW(RecordConsent(d, session, {"E02", "", "1", "console"}), InputError);
}

TEST(Audit, AnAbortWhilePlacingSamplesIsTheExperimentersAtThatTrial) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  ui.abort_placement = true;
  auto o = PersonRun(dir.File("s.db"), "P08", &ui);
  o.consent_confirmed_by = "E01";
  EXPECT_EQ(RunStudy(p, o).status, db::SessionStatus::kAborted);
  int aborts = 0;
  for (const auto& e : EventsOf(o.db_path, "P08")) {
    if (e.kind != db::EventKind::kAbort) continue;
    ++aborts;
    EXPECT_EQ(e.established_by, source::kConsole) << e.detail;
    EXPECT_TRUE(e.trial_id.has_value()) << "the trial whose samples were being placed";
    EXPECT_NE(e.detail.find("placing the samples"), std::string::npos) << e.detail;
  }
  EXPECT_EQ(aborts, 1);
}

TEST(Audit, ASignalWhilePlacingSamplesIsRecordedAsTheSignalNotAsTheExperimenter) {
  struct ClearStop {
    ~ClearStop() { RequestStop(0); }
  } clear;
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  ui.signal_at_placement = true;
  auto o = PersonRun(dir.File("s.db"), "P10", &ui);
  o.consent_confirmed_by = "E01";
  EXPECT_EQ(RunStudy(p, o).status, db::SessionStatus::kAborted);
  int interrupted = 0;
  for (const auto& e : EventsOf(o.db_path, "P10")) {
    EXPECT_NE(e.kind, db::EventKind::kAbort) << "nobody aborted: " << e.detail;
    if (e.kind != db::EventKind::kInterrupted) continue;
    ++interrupted;
    EXPECT_EQ(e.established_by, source::kSignal);
    EXPECT_NE(e.detail.find("SIGINT"), std::string::npos) << e.detail;
  }
  EXPECT_EQ(interrupted, 1);
}

TEST(Audit, ASignalWhileTheConsoleAsksForConsentIsNotBadInputAndRecordsNothing) {
  struct ClearStop {
    ~ClearStop() { RequestStop(0); }
  } clear;
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  ui.signal_at_consent = true;
  const auto o = PersonRun(dir.File("s.db"), "P11", &ui);
  try {
    RunStudy(p, o);
    ADD_FAILURE() << "the session ran";
  } catch (const InputError& e) {
    ADD_FAILURE() << "a signal is not bad input: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("SIGTERM"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(EventsOf(o.db_path, "P11").empty());
}

TEST(Audit, ACodeWithANameIsRefusedWhereverItIsGiven) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  auto o = PersonRun(dir.File("s.db"), "P09", &ui);
  // A digit does not make a name a code: the database's rule (no more than 3 letters in a
  // row), which the console applies too (runner/ui ConfirmConsent).
  o.consent_confirmed_by = "Smith1";
  try {
    RunStudy(p, o);
    ADD_FAILURE() << "Smith1 was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().at(0).field, "consent_confirmed_by");
    EXPECT_NE(std::string(e.what()).find("more than 3 letters"), std::string::npos) << e.what();
  }
}

TEST(Audit, RatingsAreStoredAsTheScalesValues) {
  // Independent values: the decimal on the scale's step.
  EXPECT_EQ(ScaleValue(static_cast<double>(0.8f) * 100, 0, 100), 80.0);
  EXPECT_EQ(ScaleValue(79.5, 0, 100), 80.0);
  EXPECT_EQ(ScaleValue(120, 0, 100), 100.0);
  EXPECT_EQ(ScaleValue(static_cast<double>(0.37f), 0, 1), 0.37);
  EXPECT_EQ(ScaleValue(3.14159, 1, 7), 3.14);
  EXPECT_EQ(ScaleValue(-3.2, -10, 10), -3.2);
  EXPECT_EQ(ScaleValue(437.0, 0, 1000), 440.0);  // a step of 10 on 0..1000
  // Through a session: the window's float positions are stored as 80 and 37.
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  ScriptedUi ui;
  auto o = PersonRun(dir.File("s.db"), "P07", &ui);
  o.consent_confirmed_by = "E01";
  RunStudy(p, o);
  db::Database d(o.db_path, {.create = false, .read_only = true});
  const auto part = d.FindParticipant(d.Studies()[0].id, "P07");
  int rated = 0;
  for (const auto& t : d.Trials(d.Sessions(part->id).at(0).id))
    for (const auto& r : d.Ratings(t.id)) {
      ++rated;
      EXPECT_EQ(r.score, r.criterion == "roughness" ? 80.0 : 37.0) << r.criterion;
    }
  EXPECT_EQ(rated, 4);  // 2 rated trials x 2 criteria
}

TEST(Audit, EveryFaultedAttemptIsPrintedCountedAndNamesItsCause) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  RunOptions o;
  o.db_path = dir.File("f.db");
  o.participant = "P08";
  o.record = RecordMode::kNone;
  o.fault_rate = 0.3;
  std::vector<std::string> warned;
  o.warn = [&](const std::string& s) { warned.push_back(s); };
  const auto s = RunStudy(p, o);
  ASSERT_EQ(s.status, db::SessionStatus::kCompleted);
  ASSERT_GT(s.faults, 0) << "no fault injected: the test tests nothing";
  EXPECT_EQ(static_cast<int>(warned.size()), s.faults);
  for (const auto& w : warned) {
    EXPECT_NE(w.find("trial "), std::string::npos) << w;
    EXPECT_NE(w.find("re-queued"), std::string::npos) << w;
    EXPECT_NE(w.find("disconnect"), std::string::npos) << "the cause: " << w;
  }
  int requeued = 0, injected = 0;
  for (const auto& e : EventsOf(o.db_path, "P08")) {
    requeued += e.kind == db::EventKind::kAttemptFaulted;
    injected += e.kind == db::EventKind::kDeviceFault && e.established_by == source::kInjected;
  }
  EXPECT_EQ(requeued, s.faults);
  EXPECT_GE(injected, s.faults) << "a simulated fault says it was simulated";
  const auto st = StudyStatus(o.db_path);
  ASSERT_EQ(st.size(), 1u);
  EXPECT_EQ(st[0].faulted, s.faults);
  EXPECT_EQ(st[0].completed, st[0].planned);
}

}  // namespace
}  // namespace hapticlab::runner::audit_test
