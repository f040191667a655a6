// Database: studies, participants and sessions.
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <openssl/evp.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/participant_code.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "schema.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::Stmt;

std::int64_t Database::CreateStudy(const Study& st) {
  HL_REQUIRE(!st.name.empty(), "study name must not be empty");
  Stmt s(db_,
         "INSERT INTO study(name, protocol_toml, protocol_hash, seed, protocol_canonical_sha256) "
         "VALUES (?,?,?,?,?)");
  s.Bind(1, st.name)
      .Bind(2, st.protocol_toml)
      .Bind(3, st.protocol_hash.empty() ? HashText(st.protocol_toml) : st.protocol_hash)
      .Bind(4, static_cast<std::int64_t>(st.seed))
      .Bind(5, st.protocol_canonical_sha256)
      .Run();
  return sqlite3_last_insert_rowid(db_);
}

std::optional<Study> Database::FindStudy(const std::string& name) const {
  for (auto& s : Studies())
    if (s.name == name) return s;
  return std::nullopt;
}

std::vector<Study> Database::Studies() const {
  Stmt s(
      db_,
      "SELECT id, name, protocol_toml, protocol_hash, seed, protocol_canonical_sha256 FROM study "
      "ORDER BY id");
  std::vector<Study> out;
  while (s.Step())
    out.push_back({s.Int(0), s.Text(1), s.Text(2), s.Text(3), static_cast<std::uint64_t>(s.Int(4)),
                   s.Text(5)});
  return out;
}

void Database::SetStudyCanonicalHash(std::int64_t study_id, const std::string& sha256) {
  Stmt s(db_, "UPDATE study SET protocol_canonical_sha256=? WHERE id=?");
  s.Bind(1, sha256).Bind(2, study_id).Run();
}

bool Database::IsReserved(std::int64_t participant_id) const {
  Stmt s(db_, "SELECT count(*) FROM session WHERE participant_id=?");
  s.Bind(1, participant_id);
  return s.Step() && s.Int(0) == 0;
}

std::int64_t Database::AddParticipant(const Participant& p) {
  // Whatever the protocol's pattern allowed: the record holds no names, dates or numbers.
  if (const std::string why = PseudonymousCodeProblem(p.code); !why.empty())
    throw InputError("<command line>", 0, "participant",
                     "'" + p.code + "' is not a pseudonymous code (" + why +
                         "): use 1-32 letters, digits, '-' or '_' with at least one digit, no "
                         "more than 3 letters in a row and at most 5 digits (e.g. P07); never a "
                         "name, birth date or phone number");
  Stmt s(db_, "INSERT INTO participant(study_id, code, idx, seed) VALUES (?,?,?,?)");
  s.Bind(1, p.study_id)
      .Bind(2, p.code)
      .Bind(3, p.index)
      .Bind(4, static_cast<std::int64_t>(p.seed))
      .Run();
  return sqlite3_last_insert_rowid(db_);
}

std::optional<Participant> Database::FindParticipant(std::int64_t study_id,
                                                     const std::string& code) const {
  Stmt s(db_, "SELECT id, study_id, code, idx, seed FROM participant WHERE study_id=? AND code=?");
  s.Bind(1, study_id).Bind(2, code);
  if (!s.Step()) return std::nullopt;
  return Participant{s.Int(0), s.Int(1), s.Text(2), static_cast<int>(s.Int(3)),
                     static_cast<std::uint64_t>(s.Int(4))};
}

std::vector<Participant> Database::Participants(std::int64_t study_id) const {
  Stmt s(db_,
         "SELECT id, study_id, code, idx, seed FROM participant WHERE study_id=? ORDER BY idx, id");
  s.Bind(1, study_id);
  std::vector<Participant> out;
  while (s.Step())
    out.push_back({s.Int(0), s.Int(1), s.Text(2), static_cast<int>(s.Int(3)),
                   static_cast<std::uint64_t>(s.Int(4))});
  return out;
}

std::int64_t Database::StartSession(const Session& se) {
  if (const std::string why = SiteCodeProblem(se.site_code); !why.empty())
    throw InputError("<command line>", 0, "site",
                     "'" + se.site_code + "' is not a site code (" + why +
                         "): use up to 8 letters, digits, '-' or '_' with a digit and no more "
                         "than 3 letters in a row (e.g. S02); never a lab's or a town's name");
  Stmt s(db_,
         "INSERT INTO session(participant_id, status, software_version, device, calibration, "
         "provenance_json, plan_json, actuator, screens, rater, site_code) "
         "VALUES (?,?,?,?,?,?,?,?,?,?,?)");
  s.Bind(1, se.participant_id)
      .Bind(2, std::string(NameOf(kSessionStatusNames, se.status)))
      .Bind(3, se.software_version)
      .Bind(4, se.device)
      .Bind(5, se.calibration)
      .Bind(6, se.provenance_json.empty() ? std::string("{}") : se.provenance_json)
      .Bind(7, se.plan_json.empty() ? std::string("[]") : se.plan_json)
      .Bind(8, se.actuator)
      .Bind(9, static_cast<std::int64_t>(se.screens))
      .Bind(10, se.rater)
      .Bind(11, se.site_code)
      .Run();
  return sqlite3_last_insert_rowid(db_);
}

void Database::SetSessionMode(std::int64_t session_id, const std::string& device,
                              const std::string& actuator, bool screens, const std::string& rater) {
  Stmt s(db_, "UPDATE session SET device=?, actuator=?, screens=?, rater=? WHERE id=?");
  s.Bind(1, device)
      .Bind(2, actuator)
      .Bind(3, static_cast<std::int64_t>(screens))
      .Bind(4, rater)
      .Bind(5, session_id)
      .Run();
}

void Database::EndSession(std::int64_t session_id, SessionStatus status) {
  Stmt s(db_,
         "UPDATE session SET status=?, ended_at=strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE id=?");
  s.Bind(1, std::string(NameOf(kSessionStatusNames, status))).Bind(2, session_id).Run();
}

void Database::ReopenSession(std::int64_t session_id) {
  Stmt s(db_, "UPDATE session SET status=?, ended_at=NULL WHERE id=?");
  s.Bind(1, std::string(NameOf(kSessionStatusNames, SessionStatus::kRunning)))
      .Bind(2, session_id)
      .Run();
}

std::vector<Session> Database::Sessions(std::int64_t participant_id) const {
  Stmt s(db_,
         "SELECT id, participant_id, started_at, coalesce(ended_at,''), status, software_version, "
         "device, calibration, provenance_json, plan_json, actuator, screens, rater, site_code "
         "FROM session "
         "WHERE participant_id=? "
         "ORDER BY id");
  s.Bind(1, participant_id);
  std::vector<Session> out;
  while (s.Step()) {
    Session x;
    x.id = s.Int(0);
    x.participant_id = s.Int(1);
    x.started_at = s.Text(2);
    x.ended_at = s.Text(3);
    x.status = ParseName(kSessionStatusNames, s.Text(4), path_, 0, "session.status");
    x.software_version = s.Text(5);
    x.device = s.Text(6);
    x.calibration = s.Text(7);
    x.provenance_json = s.Text(8);
    x.plan_json = s.Text(9);
    x.actuator = s.Text(10);
    x.screens = s.Int(11) != 0;
    x.rater = s.Text(12);
    x.site_code = s.Text(13);
    out.push_back(std::move(x));
  }
  return out;
}

}  // namespace hapticlab::db
