// Database: trials, ratings and events.
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
#include <string>
#include <thread>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "schema.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::Stmt;
using internal::Transaction;

namespace {

// A trial as a person knows it: "participant P01 trial 5" (its 1-based number in the
// participant's plan), never its database id.
std::string TrialName(sqlite3* db, std::int64_t trial_id) {
  Stmt s(db,
         "SELECT p.code, t.plan_index + 1 FROM trial t JOIN session se ON se.id = t.session_id "
         "JOIN participant p ON p.id = se.participant_id WHERE t.id = ?");
  s.Bind(1, trial_id);
  if (!s.Step()) return fmt::format("trial (row {}, no longer in the database)", trial_id);
  return fmt::format("participant {} trial {}", s.Text(0), s.Int(1));
}

}  // namespace

namespace {

// Runs `UPDATE trial SET <assignments> WHERE id=? AND status<>'completed'` on one trial and
// throws, naming the database and the trial (then `consequence`), when no trial that is still
// open has that id: a completed trial is never started or completed again.
void UpdateOpenTrial(sqlite3* db, const std::string& path, std::int64_t trial_id,
                     const std::string& assignments, const std::string& consequence) {
  const std::string sql = "UPDATE trial SET " + assignments + " WHERE id=? AND status<>'completed'";
  Stmt s(db, sql.c_str());
  s.Bind(1, trial_id).Run();
  if (sqlite3_changes(db) != 1)
    throw std::runtime_error(path + ": trial " + std::to_string(trial_id) +
                             " does not exist or is already completed" + consequence);
}

}  // namespace

namespace {

// A trial row; a status this build does not know is bad input naming the file.
Trial ReadTrial(const Stmt& s, const std::string& path) {
  Trial t;
  t.id = s.Int(0);
  t.session_id = s.Int(1);
  t.plan_index = static_cast<int>(s.Int(2));
  t.phase = ParseName(kPhaseKindNames, s.Text(3), path, 0, "trial.phase");
  t.material = s.Text(4);
  t.comparison = s.Text(5);
  t.method = s.Text(6);
  t.repetition = static_cast<int>(s.Int(7));
  t.left = s.Text(8);
  t.right = s.Text(9);
  t.status = ParseName(kTrialStatusNames, s.Text(10), path, 0, "trial.status");
  t.attempts = static_cast<int>(s.Int(11));
  t.completed_attempt = s.IsNull(12) ? 0 : static_cast<int>(s.Int(12));
  return t;
}

}  // namespace

namespace {
constexpr const char* kInsertTrial =
    "INSERT INTO trial(session_id, plan_index, phase, material, comparison, method, repetition, "
    "left_stimulus, right_stimulus, status, attempts) VALUES (?,?,?,?,?,?,?,?,?,?,?)";
void BindTrial(Stmt& s, const Trial& t) {
  s.Bind(1, t.session_id)
      .Bind(2, t.plan_index)
      .Bind(3, std::string(NameOf(kPhaseKindNames, t.phase)))
      .Bind(4, t.material)
      .Bind(5, t.comparison)
      .Bind(6, t.method)
      .Bind(7, t.repetition)
      .Bind(8, t.left)
      .Bind(9, t.right)
      .Bind(10, std::string(NameOf(kTrialStatusNames, t.status)))
      .Bind(11, t.attempts);
}
}  // namespace

std::int64_t Database::AddTrial(const Trial& t) {
  Stmt s(db_, kInsertTrial);
  BindTrial(s, t);
  s.Run();
  return sqlite3_last_insert_rowid(db_);
}

int Database::StartTrial(std::int64_t trial_id) {
  UpdateOpenTrial(db_, path_, trial_id,
                  "status='running', attempts=attempts+1, "
                  "started_at=strftime('%Y-%m-%dT%H:%M:%fZ','now')",
                  "");
  return CurrentAttempt(trial_id);
}

int Database::CurrentAttempt(std::int64_t trial_id) const {
  Stmt s(db_, "SELECT attempts FROM trial WHERE id=?");
  s.Bind(1, trial_id);
  if (!s.Step()) throw std::runtime_error(path_ + ": no trial " + std::to_string(trial_id));
  return static_cast<int>(s.Int(0));
}

void Database::SetTrialStatus(std::int64_t trial_id, TrialStatus status) {
  Stmt s(db_, "UPDATE trial SET status=? WHERE id=?");
  s.Bind(1, std::string(NameOf(kTrialStatusNames, status))).Bind(2, trial_id).Run();
  if (sqlite3_changes(db_) != 1)
    throw std::runtime_error(path_ + ": no trial " + std::to_string(trial_id));
}

void Database::CompleteTrial(std::int64_t trial_id, const std::vector<Rating>& ratings,
                             const std::vector<StreamReport>& streams) {
  Transaction tx(db_);
  const int attempt = CurrentAttempt(trial_id);
  // Every recorded stream of this attempt must be whole and stored exactly once.
  if (!streams.empty()) {
    std::vector<std::string> problems;
    std::vector<std::pair<std::string, std::int64_t>> stored;  // stream, samples in chunks
    {
      Stmt q(db_,
             "SELECT stream, sum(sample_count) FROM trajectory_chunk WHERE trial_id=? AND "
             "attempt=? GROUP BY stream ORDER BY stream");
      q.Bind(1, trial_id).Bind(2, attempt);
      while (q.Step()) stored.emplace_back(q.Text(0), q.Int(1));
    }
    auto stored_of = [&](const std::string& name) -> std::int64_t {
      for (const auto& [n, c] : stored)
        if (n == name) return c;
      return 0;
    };
    std::vector<std::string> reported;
    for (const auto& r : streams) {
      if (r.trial_id != trial_id || r.attempt != attempt) continue;
      reported.push_back(r.stream);
      const auto kept = r.samples_offered - std::min(r.samples_dropped, r.samples_offered);
      const auto in_db = stored_of(r.stream);
      if (r.samples_written != kept || static_cast<std::uint64_t>(in_db) != r.samples_written)
        problems.push_back(fmt::format(
            "stream {}: {} samples queued, {} committed by the writer, {} stored{}", r.stream, kept,
            r.samples_written, in_db, r.error.empty() ? "" : " (" + r.error + ")"));
    }
    for (const auto& [n, c] : stored)
      if (std::find(reported.begin(), reported.end(), n) == reported.end())
        problems.push_back(
            fmt::format("stream {}: {} samples stored that no stream of attempt {} "
                        "reported (another process wrote this trial)",
                        n, c, attempt));
    if (!problems.empty())
      throw TrajectoryIncomplete(fmt::format("{}: {} attempt {}: trajectories not whole: {}", path_,
                                             TrialName(db_, trial_id), attempt,
                                             fmt::join(problems, "; ")));
    Stmt ins(db_,
             "INSERT INTO trajectory_stream(trial_id, attempt, stream, rate_hz, samples_offered, "
             "samples_dropped, samples_written) VALUES (?,?,?,?,?,?,?)");
    for (const auto& r : streams) {
      if (r.trial_id != trial_id || r.attempt != attempt) continue;
      ins.Bind(1, trial_id)
          .Bind(2, attempt)
          .Bind(3, r.stream)
          .Bind(4, r.rate_hz)
          .Bind(5, static_cast<std::int64_t>(r.samples_offered))
          .Bind(6, static_cast<std::int64_t>(r.samples_dropped))
          .Bind(7, static_cast<std::int64_t>(r.samples_written));
      ins.Run();
      ins.Reset();
    }
  }
  // A rating without a source is the session's rater's.
  Stmt ins(
      db_,
      "INSERT INTO rating(trial_id, criterion, score, response_time_s, source) VALUES (?,?,?,?, "
      "coalesce(nullif(?,''), (SELECT s.rater FROM trial t JOIN session s ON s.id = t.session_id "
      "WHERE t.id = ?1)))");
  for (const auto& r : ratings) {
    ins.Bind(1, trial_id)
        .Bind(2, r.criterion)
        .Bind(3, r.score)
        .Bind(4, r.response_time_s)
        .Bind(5, r.source);
    ins.Run();
    ins.Reset();
  }
  // The completion marker commits with the ratings; a completed trial cannot be completed again.
  UpdateOpenTrial(db_, path_, trial_id,
                  "status='completed', completed_attempt=attempts, "
                  "completed_at=strftime('%Y-%m-%dT%H:%M:%fZ','now')",
                  "; ratings not stored");
  tx.Commit();
}

std::vector<StreamReport> Database::StreamChecks(std::int64_t trial_id) const {
  Stmt s(db_,
         "SELECT c.trial_id, c.attempt, c.stream, c.rate_hz, c.samples_offered, c.samples_dropped, "
         "c.samples_written FROM trajectory_stream c JOIN trial t ON t.id = c.trial_id "
         "WHERE c.trial_id=? AND c.attempt = t.completed_attempt ORDER BY c.stream");
  s.Bind(1, trial_id);
  std::vector<StreamReport> out;
  while (s.Step()) {
    StreamReport r;
    r.trial_id = s.Int(0);
    r.attempt = static_cast<int>(s.Int(1));
    r.stream = s.Text(2);
    r.rate_hz = s.Real(3);
    r.samples_offered = static_cast<std::uint64_t>(s.Int(4));
    r.samples_dropped = static_cast<std::uint64_t>(s.Int(5));
    r.samples_written = static_cast<std::uint64_t>(s.Int(6));
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<Trial> Database::Trials(std::int64_t session_id) const {
  Stmt s(db_,
         "SELECT id, session_id, plan_index, phase, material, comparison, method, repetition, "
         "left_stimulus, right_stimulus, status, attempts, completed_attempt FROM trial "
         "WHERE session_id=? "
         "ORDER BY plan_index, id");
  s.Bind(1, session_id);
  std::vector<Trial> out;
  while (s.Step()) out.push_back(ReadTrial(s, path_));
  return out;
}

std::vector<Rating> Database::Ratings(std::int64_t trial_id) const {
  Stmt s(
      db_,
      "SELECT criterion, score, response_time_s, source FROM rating WHERE trial_id=? ORDER BY id");
  s.Bind(1, trial_id);
  std::vector<Rating> out;
  while (s.Step()) {
    // SQLite stores any type in a REAL column; text or NULL is damage, never a score of 0.
    for (int col : {1, 2})
      if (!s.IsNumber(col) || !std::isfinite(s.Real(col)))
        throw InputError(
            path_, 0, col == 1 ? "rating.score" : "rating.response_time_s",
            fmt::format("{} criterion '{}': '{}' is not a finite number", TrialName(db_, trial_id),
                        s.Text(0), s.IsNull(col) ? "NULL" : s.Text(col)));
    out.push_back({s.Text(0), s.Real(1), s.Real(2), s.Text(3)});
  }
  return out;
}

std::vector<std::int64_t> Database::RatedTrialsInCompletionOrder(std::int64_t session_id) const {
  Stmt s(db_,
         "SELECT r.trial_id FROM rating r JOIN trial t ON r.trial_id = t.id WHERE t.session_id = ? "
         "GROUP BY r.trial_id ORDER BY MIN(r.id)");
  s.Bind(1, session_id);
  std::vector<std::int64_t> out;
  while (s.Step()) out.push_back(s.Int(0));
  return out;
}

std::int64_t Database::LogEvent(const Event& e) {
  HL_REQUIRE(e.kind != EventKind::kUnnamed, "every event names its kind (db::Event::kind)");
  Stmt s(db_,
         "INSERT INTO event(session_id, trial_id, kind, detail, established_by) VALUES "
         "(?,?,?,?,?)");
  s.Bind(1, e.session_id);
  if (e.trial_id)
    s.Bind(2, *e.trial_id);
  else
    s.BindNull(2);
  s.Bind(3, std::string(NameOf(kEventKindNames, e.kind)))
      .Bind(4, e.detail)
      .Bind(5, e.established_by.empty() ? std::string("hapticlab") : e.established_by)
      .Run();
  return sqlite3_last_insert_rowid(db_);
}

std::vector<Event> Database::Events(std::int64_t session_id) const {
  Stmt s(db_,
         "SELECT id, session_id, trial_id, kind, detail, created_at, established_by FROM event "
         "WHERE session_id=? ORDER BY id");
  s.Bind(1, session_id);
  std::vector<Event> out;
  while (s.Step()) {
    Event e{s.Int(0),     s.Int(1),
            std::nullopt, ParseName(kEventKindNames, s.Text(3), path_, 0, "event.kind"),
            s.Text(4),    s.Text(5),
            s.Text(6)};
    if (!s.IsNull(2)) e.trial_id = s.Int(2);
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace hapticlab::db
