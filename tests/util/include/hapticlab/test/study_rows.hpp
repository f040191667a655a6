#pragma once
// Rows for the tests that write a study record: the study, participant and session most of
// them hang their trials from, and planned trials, one Database::AddTrial each (the runner adds
// a session's plan the same way, inside its own transaction). Header-only: hl_test_util does
// not link the db module; the tests that include this do.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"

namespace hapticlab::test {

/// The ids AddStudySession wrote.
struct SessionRows {
  std::int64_t study = 0, participant = 0, session = 0;
};

/// `study`, one participant `code` in it, and a session of that participant (the session's
/// other fields at their defaults).
inline SessionRows AddStudySession(
    db::Database& d, const db::Study& study = {.name = "s", .protocol_toml = "x", .seed = 1},
    const std::string& code = "P01") {
  SessionRows r;
  r.study = d.CreateStudy(study);
  r.participant = d.AddParticipant({.study_id = r.study, .code = code});
  r.session = d.StartSession({.participant_id = r.participant});
  return r;
}

// The rows of a file held at an earlier schema (Database's {.migrate_to}) are written in SQL
// that every schema version accepts (the API writes today's columns).

/// One row in each table that exists at schema `version` (1 or later): study 1, participant
/// P01, its session, a planned main trial of Denim with one rating, and from version 2 an event.
inline void InsertOneRowEach(db::Database& d, int version) {
  d.Exec("INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('s','p','h',7)");
  d.Exec("INSERT INTO participant(study_id, code, idx, seed) VALUES (1,'P01',0,11)");
  d.Exec("INSERT INTO session(participant_id) VALUES (1)");
  d.Exec("INSERT INTO trial(session_id, plan_index, phase, material) VALUES (1,0,'main','Denim')");
  d.Exec(
      "INSERT INTO rating(trial_id, criterion, score, response_time_s) VALUES "
      "(1,'overall',61.5,2.0)");
  if (version >= 2) d.Exec("INSERT INTO event(session_id, kind) VALUES (1,'break')");
}

/// Study 1 with participants P01 and P02: session 1 of P01 on `device1`, session 2 of P02 on
/// `device2` (schema 1 or later).
inline void InsertTwoSessions(db::Database& old, const std::string& device1,
                              const std::string& device2) {
  old.Exec("INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('s','p','h',7)");
  old.Exec(
      "INSERT INTO participant(study_id, code, idx, seed) VALUES (1,'P01',0,11), (1,'P02',1,12)");
  old.Exec("INSERT INTO session(participant_id, device) VALUES (1,'" + device1 + "'), (2,'" +
           device2 + "')");
}

inline std::vector<std::int64_t> AddTrials(db::Database& d, const std::vector<db::Trial>& trials) {
  std::vector<std::int64_t> ids;
  for (const auto& t : trials) ids.push_back(d.AddTrial(t));
  return ids;
}

}  // namespace hapticlab::test
