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

inline std::vector<std::int64_t> AddTrials(db::Database& d, const std::vector<db::Trial>& trials) {
  std::vector<std::int64_t> ids;
  for (const auto& t : trials) ids.push_back(d.AddTrial(t));
  return ids;
}

}  // namespace hapticlab::test
