// A study's rows: the protocol's identity by content (comments and formatting do not count, a
// changed key is refused by name with both values, older databases keep working) and codes
// reserved by `participant new`.

#include "hapticlab/runner/study_record.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/canonical.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::study_record_test {
namespace {

namespace fs = std::filesystem;

// The small test protocol as a file of `dir` (with its profiles), edited by `edit`.
protocols::Protocol Written(test::TempDir& dir, const std::string& name,
                            const std::function<void(std::string*)>& edit = {}) {
  if (!fs::exists(dir.File("profiles.toml")))
    fs::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("profiles.toml"));
  std::string text = test::ReadFile(test::DataPath("protocols/small.toml"));
  if (edit) edit(&text);
  test::WriteFile(dir.File(name), text);
  return protocols::LoadProtocol(dir.File(name));
}

std::string Refusal(db::Database& d, const protocols::Protocol& p) {
  try {
    (void)FindOrCreateStudy(d, p, "s.db");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(StudyRecord, ACommentContinuesAChangedRepetitionCountIsRefusedByName) {
  test::TempDir dir;
  const auto p = Written(dir, "p.toml");
  const auto commented = Written(dir, "c.toml", [](std::string* t) {
    t->insert(t->find("[[phase]]"), "# the phases, as piloted on 2026-11-20\n");
  });
  const auto changed = Written(dir, "r.toml", [](std::string* t) {
    t->replace(t->find("repetitions = 2"), 15, "repetitions = 3");
  });
  ASSERT_NE(p.text, commented.text);
  db::Database d(dir.File("s.db"));
  const auto id = FindOrCreateStudy(d, p, "s.db");
  EXPECT_EQ(d.Studies()[0].protocol_canonical_sha256, ProtocolIdentity(p));
  EXPECT_EQ(FindOrCreateStudy(d, commented, "s.db"), id);
  EXPECT_EQ(ProtocolIdentity(commented), ProtocolIdentity(p));
  const std::string why = Refusal(d, changed);
  EXPECT_NE(why.find("s.db: study: study 'test-small' in this database was run with a different "
                     "protocol"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("phase[2].repetitions: 2 -> 3"), std::string::npos) << why;
  EXPECT_EQ(d.Studies().size(), 1u);
}

// A database written before schema v7 holds the raw text and its hash only: the identity
// of the recorded text is computed, compared and stored.
TEST(StudyRecord, AnOlderDatabaseIsComparedByTheContentOfItsRecordedText) {
  test::TempDir dir;
  const auto p = Written(dir, "p.toml");
  const auto commented = Written(dir, "c.toml", [](std::string* t) { *t += "\n# the end\n"; });
  const auto changed = Written(
      dir, "r.toml", [](std::string* t) { t->replace(t->find("seed = 42"), 9, "seed = 43"); });
  {
    db::Database old(dir.File("s.db"), {.migrate_to = 6});
    old.Exec("INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('test-small', '" +
             p.text + "', '" + db::HashText(p.text) + "', 42)");
  }
  db::Database d(dir.File("s.db"));  // migrated to v8: no identity yet
  ASSERT_EQ(d.Studies()[0].protocol_canonical_sha256, "");
  EXPECT_NE(Refusal(d, changed).find("study.seed: 42 -> 43"), std::string::npos);
  EXPECT_EQ(d.Studies()[0].protocol_canonical_sha256, "");  // nothing stored on a refusal
  EXPECT_EQ(FindOrCreateStudy(d, commented, "s.db"), d.Studies()[0].id);
  EXPECT_EQ(d.Studies()[0].protocol_canonical_sha256, ProtocolIdentity(p));
}

TEST(StudyRecord, AnUnreadableRecordedTextFallsBackToTheRawHashAndSaysSo) {
  test::TempDir dir;
  const auto p = Written(dir, "p.toml");
  db::Database d(dir.File("s.db"));
  d.Exec(
      "INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('test-small', "
      "'not [toml', 'abc', 42)");
  const std::string why = Refusal(d, p);
  EXPECT_NE(why.find("only the raw texts could be compared"), std::string::npos) << why;
}

TEST(StudyRecord, ReservedCodesAreDistinctAndRunWithTheirPlanIndex) {
  test::TempDir dir;
  const auto p = Written(dir, "p.toml");
  const std::string db_path = dir.File("s.db");
  const auto a = ReserveParticipant(db_path, p);
  const auto b = ReserveParticipant(db_path, p);
  EXPECT_EQ(a.code, "P01");
  EXPECT_EQ(b.code, "P02");
  EXPECT_EQ(b.index, 1);
  auto status = StudyStatus(db_path);
  ASSERT_EQ(status.size(), 2u);
  EXPECT_FALSE(status[1].session_status.has_value());  // reserved: no session yet
  EXPECT_EQ(status[1].planned, 0);
  // Running the second reserved code uses its row and index; the first stays reserved.
  RunOptions o;
  o.db_path = db_path;
  o.participant = b.code;
  o.record = RecordMode::kNone;
  EXPECT_EQ(RunStudy(p, o).status, db::SessionStatus::kCompleted);
  {
    const db::Database d(db_path);
    const auto parts = d.Participants(d.Studies()[0].id);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[1].code, "P02");
    EXPECT_EQ(parts[1].index, 1);
    EXPECT_EQ(d.Sessions(parts[1].id).size(), 1u);
  }
  status = StudyStatus(db_path);
  EXPECT_FALSE(status[0].session_status.has_value());  // reserved: no session yet
  EXPECT_EQ(status[1].session_status, db::SessionStatus::kCompleted);
  // Running a completed code again is refused without sending the user to 'study resume'
  // (which refuses a completed session).
  try {
    RunStudy(p, o);
    ADD_FAILURE() << "P02 ran twice";
  } catch (const InputError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("already completed"), std::string::npos) << why;
    EXPECT_EQ(why.find("study resume"), std::string::npos) << why;
  }
  // A reserved code run with another plan index is refused; a new code takes the next index.
  o.participant = "P01";
  o.participant_index = 5;
  EXPECT_THROW(RunStudy(p, o), InputError);
  EXPECT_EQ(ReserveParticipant(db_path, p).code, "P03");
}

// Two consoles reserving at once (threads, each with its own connection) never share a code.
TEST(StudyRecord, ConcurrentReservationsNeverShareACode) {
  test::TempDir dir;
  const auto p = Written(dir, "p.toml", [](std::string* t) {
    t->replace(t->find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^NU[0-9]{3}$\"");
  });
  const std::string db_path = dir.File("s.db");
  { db::Database create(db_path); }
  std::vector<std::string> codes(6);
  std::vector<std::thread> ts;
  for (std::size_t i = 0; i < codes.size(); ++i)
    ts.emplace_back([&, i] { codes[i] = ReserveParticipant(db_path, p).code; });
  for (auto& t : ts) t.join();
  const std::set<std::string> distinct(codes.begin(), codes.end());
  EXPECT_EQ(distinct.size(), codes.size());
  EXPECT_TRUE(distinct.count("NU001") && distinct.count("NU006")) << *distinct.begin();
}

// A session's mode is read from its row once, into enums (runner/study_runner.hpp): every
// recorded name parses back to itself, "unrecorded" (before schema v5) is no actuator, and a
// name this build does not know is bad input naming the database and the column.
TEST(StudyRecord, RecordedModesParseOnceAndUnknownNamesAreBadInput) {
  for (const ActuatorKind k : {ActuatorKind::kNone, ActuatorKind::kAudio})
    EXPECT_EQ(FromName(kActuatorNames, NameOf(kActuatorNames, k)), k);
  for (const Rater& r :
       {Rater{}, Rater{RaterKind::kWindow, ""}, Rater{RaterKind::kRatingBox, "16c0:05df"}})
    EXPECT_EQ(ParseRater(r.Name(), "s.db", "rater"), r) << r.Name();
  EXPECT_EQ(Rater{}.Name(), "simulated");
  EXPECT_EQ((Rater{RaterKind::kRatingBox, "16c0:05df"}.Name()), "rating-box:16c0:05df");
  EXPECT_EQ(RaterOf(false, "16c0:05df"), Rater{});  // no screens: the simulated observer
  EXPECT_EQ(RaterOf(true, "").kind, RaterKind::kWindow);
  for (const char* bad : {"Window", "rating-box:", "rating-box", ""})
    EXPECT_THROW(ParseRater(bad, "s.db", "rater"), InputError) << bad;

  test::TempDir dir;
  const std::string db_path = dir.File("s.db");
  const auto record = [&](const std::string& code, const std::string& actuator,
                          const std::string& rater) {
    db::Database d(db_path);
    const auto studies = d.Studies();
    const auto st = studies.empty() ? d.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1})
                                    : studies[0].id;
    const auto id = d.AddParticipant({.study_id = st, .code = code});
    d.StartSession({.participant_id = id,
                    .device = "sim",
                    .actuator = actuator,
                    .screens = true,
                    .rater = rater});
  };
  record("P01", "audio", "rating-box:16c0:05df");
  record("P02", "unrecorded", "window");
  record("P03", "vibrator", "window");
  record("P04", "none", "keyboard");
  const SessionMode p1 = RecordedMode(db_path, "P01");
  EXPECT_EQ(p1.actuator, ActuatorKind::kAudio);
  EXPECT_EQ(p1.rater, (Rater{RaterKind::kRatingBox, "16c0:05df"}));
  EXPECT_EQ(p1.Describe(),
            "device sim, actuator audio, screens on, ratings by the participant "
            "(rating-box:16c0:05df)");
  const SessionMode p2 = RecordedMode(db_path, "P02");
  EXPECT_FALSE(p2.actuator.has_value());
  EXPECT_EQ(p2.Describe(),
            "device sim, actuator unrecorded, screens on, ratings by the participant (window)");
  // An unrecorded actuator matches any on resume; a recorded one does not.
  SessionMode now = p2;
  now.actuator = ActuatorKind::kAudio;
  EXPECT_FALSE(CheckResumeMode(p2, now, false, db_path, "P02"));
  const SessionMode no_actuator{.device = "sim", .screens = true, .rater = p1.rater};
  EXPECT_THROW(CheckResumeMode(p1, no_actuator, false, db_path, "P01"), InputError);
  EXPECT_TRUE(CheckResumeMode(p1, no_actuator, true, db_path, "P01"));  // allowed, and it differs
  for (const auto& [code, field] :
       {std::pair{"P03", "session.actuator"}, std::pair{"P04", "session.rater"}}) {
    try {
      (void)RecordedMode(db_path, code);
      ADD_FAILURE() << code << ": an unknown name was accepted";
    } catch (const InputError& e) {
      ASSERT_FALSE(e.diagnostics().empty());
      EXPECT_EQ(e.diagnostics()[0].file, db_path) << code;
      EXPECT_EQ(e.diagnostics()[0].field, field) << code;
    }
  }
}

}  // namespace
}  // namespace hapticlab::runner::study_record_test
