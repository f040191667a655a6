#include "hapticlab/db/database.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cctype>
#include <cmath>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "schema.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::ExecSql;
using internal::Stmt;
using internal::Transaction;

namespace {

std::string JoinChannels(const std::vector<std::string>& c) {
  std::string s;
  for (const auto& x : c) s += (s.empty() ? "" : ",") + x;
  return s;
}

std::vector<std::string> SplitChannels(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= s.size()) {
    const auto comma = s.find(',', start);
    const auto end = comma == std::string::npos ? s.size() : comma;
    if (end > start) out.push_back(s.substr(start, end - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

Trial ReadTrial(const Stmt& s) {
  Trial t;
  t.id = s.Int(0);
  t.session_id = s.Int(1);
  t.plan_index = static_cast<int>(s.Int(2));
  t.phase = s.Text(3);
  t.material = s.Text(4);
  t.comparison = s.Text(5);
  t.method = s.Text(6);
  t.repetition = static_cast<int>(s.Int(7));
  t.left = s.Text(8);
  t.right = s.Text(9);
  t.status = s.Text(10);
  t.attempts = static_cast<int>(s.Int(11));
  t.completed_attempt = s.IsNull(12) ? 0 : static_cast<int>(s.Int(12));
  return t;
}

}  // namespace

bool IsPseudonymousCode(const std::string& code) {
  if (code.empty() || code.size() > 32) return false;
  bool digit = false;
  for (unsigned char c : code) {
    if (std::isdigit(c)) digit = true;
    else if (!std::isalpha(c) && c != '-' && c != '_') return false;
  }
  return digit;
}

Database OpenForReading(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError(path, 0, "--db", "no such database file");
  std::string report;
  try {
    Database d(path, {.create = false, .read_only = true});
    report = d.QuickCheck();
    if (report == "ok" && d.SchemaVersion() < kSchemaVersion) {
      // An older file is migrated forward first (its repairs included), then read.
      { Database(path, {.create = false}); }
      return Database(path, {.create = false, .read_only = true});
    }
    if (report == "ok") return d;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    report = e.what();
  }
  if (report.size() > 400) report = report.substr(0, 400) + "...";
  throw InputError(path, 0, "",
                   "the database is damaged (SQLite quick_check failed), refused: restore it "
                   "from a backup; details: " + report);
}

std::string HashText(const std::string& text) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (EVP_Digest(text.data(), text.size(), md, &len, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 digest failed");
  static constexpr const char* kHex = "0123456789abcdef";
  std::string s;
  for (unsigned int i = 0; i < len; ++i) {
    s += kHex[md[i] >> 4];
    s += kHex[md[i] & 15];
  }
  return s;
}

namespace {

// A writer maps the -shm file; one that was made read-only or truncated by someone else
// would fault with SIGBUS inside SQLite, so it is refused here with a message, as is a
// read-only -wal (mode bits too: as root, access() would allow what the owner forbade).
void CheckSharedMemoryFile(const std::string& path) {
  const std::string wal = path + "-wal";
  struct stat ws {};
  if (::stat(wal.c_str(), &ws) == 0 && ((ws.st_mode & 0222) == 0 || ::access(wal.c_str(), W_OK) != 0))
    throw InputError(wal, 0, "--db",
                     "the database's write-ahead log is read-only; make it (and the -shm file) "
                     "writable: it may hold committed trials that are not yet in the database file");
  const std::string shm = path + "-shm";
  struct stat st {};
  if (::stat(shm.c_str(), &st) != 0) return;  // none: SQLite creates it
  if ((st.st_mode & 0222) == 0 || ::access(shm.c_str(), W_OK) != 0)
    throw InputError(shm, 0, "--db",
                     "the database's shared-memory file is read-only; make it writable (and the "
                     "-wal file) or, when no HapticLab process uses the database, delete it");
  if (st.st_size % 32768 != 0)
    throw InputError(shm, 0, "--db",
                     "the database's shared-memory file is truncated (" +
                         std::to_string(st.st_size) +
                         " bytes); when no HapticLab process uses the database, delete it");
}

// SQLite does not call the busy handler while it changes the journal mode: when several
// processes open one new file at once, all but one get SQLITE_BUSY at once. Retried here
// for as long as the busy timeout allows.
void EnterWalMode(sqlite3* db, int busy_timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(busy_timeout_ms);
  for (;;) {
    const int rc = sqlite3_exec(db, "PRAGMA journal_mode = WAL", nullptr, nullptr, nullptr);
    if (rc == SQLITE_OK) return;
    if ((rc & 0xff) != SQLITE_BUSY || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ExecSql(db, "PRAGMA journal_mode = WAL");  // once more, for its error message
}

}  // namespace

Database::Database(const std::string& path, const OpenOptions& options) : path_(path) {
  if (!options.read_only) CheckSharedMemoryFile(path);
  int flags = options.read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
  if (options.create && !options.read_only) flags |= SQLITE_OPEN_CREATE;
  if (sqlite3_open_v2(path.c_str(), &db_, flags | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(path + ": cannot open database: " + msg);
  }
  sqlite3_busy_timeout(db_, options.busy_timeout_ms);
  try {
    ExecSql(db_, "PRAGMA foreign_keys = ON");
    if (!options.read_only) {
      EnterWalMode(db_, options.busy_timeout_ms);
      // FULL: a committed transaction survives power loss, not only a process crash.
      ExecSql(db_, "PRAGMA synchronous = FULL");
      Migrate(options.migrate_to);
    } else {
      const int v = SchemaVersion();
      if (v > kSchemaVersion)
        throw std::runtime_error(path + ": schema version " + std::to_string(v) +
                                 " is newer than this build supports (" +
                                 std::to_string(kSchemaVersion) + ")");
    }
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

Database::~Database() {
  if (db_) sqlite3_close(db_);
}
Database::Database(Database&& o) noexcept : path_(std::move(o.path_)), db_(std::exchange(o.db_, nullptr)) {}
Database& Database::operator=(Database&& o) noexcept {
  if (this != &o) {
    if (db_) sqlite3_close(db_);
    path_ = std::move(o.path_);
    db_ = std::exchange(o.db_, nullptr);
  }
  return *this;
}

void Database::Exec(const std::string& sql) const { ExecSql(db_, sql.c_str()); }

int Database::SchemaVersion() const {
  Stmt has(db_, "SELECT count(*) FROM sqlite_master WHERE type='table' AND name='schema_version'");
  has.Step();
  if (has.Int(0) == 0) {
    Stmt any(db_, "SELECT count(*) FROM sqlite_master WHERE type='table'");
    any.Step();
    if (any.Int(0) != 0)
      throw std::runtime_error(path_ + ": not a HapticLab database (no schema_version table)");
    return 0;
  }
  Stmt v(db_, "SELECT max(version) FROM schema_version");
  return v.Step() && !v.IsNull(0) ? static_cast<int>(v.Int(0)) : 0;
}

void Database::Migrate(int target) {
  if (target < 0 || target > kSchemaVersion)
    throw std::invalid_argument("schema version " + std::to_string(target) + " does not exist");
  auto refuse_newer = [&](int v) {
    if (v > kSchemaVersion)
      throw std::runtime_error(path_ + ": schema version " + std::to_string(v) +
                               " is newer than this build supports (" +
                               std::to_string(kSchemaVersion) + "); upgrade HapticLab");
  };
  const int seen = SchemaVersion();
  refuse_newer(seen);
  if (seen >= target) return;
  // Every pending migration in one write transaction: a second process opening the same new
  // file waits for it (busy timeout), then reads the version again and finds nothing to do.
  Transaction tx(db_);
  const int current = SchemaVersion();
  refuse_newer(current);
  for (int k = current + 1; k <= target; ++k) {
    if (k == 1) {
      ExecSql(db_,
              "CREATE TABLE schema_version (version INTEGER NOT NULL, applied_at TEXT NOT NULL "
              "DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')))");
    }
    ExecSql(db_, internal::MigrationSql(k));
    Stmt ins(db_, "INSERT INTO schema_version(version) VALUES (?)");
    ins.Bind(1, k).Run();
  }
  tx.Commit();
}

std::string Database::QuickCheck() const {
  Stmt s(db_, "PRAGMA quick_check");
  std::string out;
  while (s.Step()) out += (out.empty() ? "" : "\n") + s.Text(0);
  return out;
}

std::vector<std::string> Database::VerifyTrajectories() const {
  std::vector<std::string> out;
  {
    Stmt q(db_,
           "SELECT t.id, s.stream, s.samples_written, (SELECT coalesce(sum(c.sample_count), 0) "
           "FROM trajectory_chunk c WHERE c.trial_id = t.id AND c.attempt = t.completed_attempt "
           "AND c.stream = s.stream) FROM trial t JOIN trajectory_stream s ON s.trial_id = t.id "
           "AND s.attempt = t.completed_attempt WHERE t.status = 'completed' ORDER BY t.id, s.stream");
    while (q.Step())
      if (q.Int(2) != q.Int(3))
        out.push_back(fmt::format("trial {} stream {}: {} samples stored, {} at completion",
                                  q.Int(0), q.Text(1), q.Int(3), q.Int(2)));
  }
  Stmt q(db_,
         "SELECT c.trial_id, c.stream, sum(c.sample_count) FROM trajectory_chunk c JOIN trial t "
         "ON t.id = c.trial_id AND c.attempt = t.completed_attempt WHERE t.status = 'completed' "
         "AND EXISTS (SELECT 1 FROM trajectory_stream s WHERE s.trial_id = t.id AND s.attempt = "
         "t.completed_attempt) AND NOT EXISTS (SELECT 1 FROM trajectory_stream s WHERE "
         "s.trial_id = t.id AND s.attempt = t.completed_attempt AND s.stream = c.stream) "
         "GROUP BY c.trial_id, c.stream ORDER BY c.trial_id, c.stream");
  while (q.Step())
    out.push_back(fmt::format("trial {} stream {}: {} samples stored that no check covers",
                              q.Int(0), q.Text(1), q.Int(2)));
  return out;
}

std::string Database::IntegrityCheck() const {
  Stmt s(db_, "PRAGMA integrity_check");
  std::string out;
  while (s.Step()) out += (out.empty() ? "" : "\n") + s.Text(0);
  return out;
}

std::int64_t Database::CreateStudy(const Study& st) {
  HL_REQUIRE(!st.name.empty(), "study name must not be empty");
  Stmt s(db_, "INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES (?,?,?,?)");
  s.Bind(1, st.name).Bind(2, st.protocol_toml)
      .Bind(3, st.protocol_hash.empty() ? HashText(st.protocol_toml) : st.protocol_hash)
      .Bind(4, static_cast<std::int64_t>(st.seed)).Run();
  return sqlite3_last_insert_rowid(db_);
}

std::optional<Study> Database::FindStudy(const std::string& name) const {
  for (auto& s : Studies())
    if (s.name == name) return s;
  return std::nullopt;
}

std::vector<Study> Database::Studies() const {
  Stmt s(db_, "SELECT id, name, protocol_toml, protocol_hash, seed FROM study ORDER BY id");
  std::vector<Study> out;
  while (s.Step())
    out.push_back({s.Int(0), s.Text(1), s.Text(2), s.Text(3), static_cast<std::uint64_t>(s.Int(4))});
  return out;
}

std::int64_t Database::AddParticipant(const Participant& p) {
  if (!IsPseudonymousCode(p.code))
    throw InputError("", 0, "participant",
                     "'" + p.code + "' is not a pseudonymous code: use 1-32 letters, digits, "
                     "'-' or '_' including at least one digit (e.g. P07); never a name");
  Stmt s(db_, "INSERT INTO participant(study_id, code, idx, seed) VALUES (?,?,?,?)");
  s.Bind(1, p.study_id).Bind(2, p.code).Bind(3, p.index)
      .Bind(4, static_cast<std::int64_t>(p.seed)).Run();
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
  Stmt s(db_, "SELECT id, study_id, code, idx, seed FROM participant WHERE study_id=? ORDER BY idx, id");
  s.Bind(1, study_id);
  std::vector<Participant> out;
  while (s.Step())
    out.push_back({s.Int(0), s.Int(1), s.Text(2), static_cast<int>(s.Int(3)),
                   static_cast<std::uint64_t>(s.Int(4))});
  return out;
}

std::int64_t Database::StartSession(const Session& se) {
  Stmt s(db_,
         "INSERT INTO session(participant_id, status, software_version, device, calibration, "
         "provenance_json, plan_json, actuator, screens, rater) VALUES (?,?,?,?,?,?,?,?,?,?)");
  s.Bind(1, se.participant_id).Bind(2, se.status).Bind(3, se.software_version)
      .Bind(4, se.device).Bind(5, se.calibration)
      .Bind(6, se.provenance_json.empty() ? std::string("{}") : se.provenance_json)
      .Bind(7, se.plan_json.empty() ? std::string("[]") : se.plan_json)
      .Bind(8, se.actuator).Bind(9, static_cast<std::int64_t>(se.screens)).Bind(10, se.rater).Run();
  return sqlite3_last_insert_rowid(db_);
}

void Database::SetSessionMode(std::int64_t session_id, const std::string& device, const std::string& actuator,
                              bool screens, const std::string& rater) {
  Stmt s(db_, "UPDATE session SET device=?, actuator=?, screens=?, rater=? WHERE id=?");
  s.Bind(1, device).Bind(2, actuator).Bind(3, static_cast<std::int64_t>(screens)).Bind(4, rater)
      .Bind(5, session_id).Run();
}

void Database::Backup(const std::string& dest) const {
  // Refuse to overwrite: a backup over an older record (or the source) would lose it.
  struct ::stat st{};
  if (::stat(dest.c_str(), &st) == 0)
    throw InputError(dest, 0, "DEST", "already exists; a backup never overwrites a file");
  sqlite3* out = nullptr;
  if (sqlite3_open_v2(dest.c_str(), &out, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    const std::string msg = out ? sqlite3_errmsg(out) : "out of memory";
    sqlite3_close(out);
    throw InputError(dest, 0, "DEST", "cannot create: " + msg);
  }
  // Whole database in one step: the copy is one consistent snapshot of the committed state
  // (a step that copies every page holds a read transaction on the source throughout).
  sqlite3_backup* b = sqlite3_backup_init(out, "main", db_, "main");
  int rc = SQLITE_ERROR;
  if (b) {
    for (int tries = 0; tries < 200; ++tries) {
      rc = sqlite3_backup_step(b, -1);
      if (rc != SQLITE_BUSY && rc != SQLITE_LOCKED) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    sqlite3_backup_finish(b);
  }
  const std::string msg = sqlite3_errmsg(out);
  sqlite3_close(out);
  if (rc != SQLITE_DONE) {
    ::unlink(dest.c_str());
    throw InputError(dest, 0, "DEST", "backup failed: " + msg);
  }
}

bool Database::Checkpoint() {
  int log_frames = 0, checkpointed = 0;
  const int rc = sqlite3_wal_checkpoint_v2(db_, "main", SQLITE_CHECKPOINT_TRUNCATE, &log_frames, &checkpointed);
  return rc == SQLITE_OK;
}

void Database::EndSession(std::int64_t session_id, const std::string& status) {
  Stmt s(db_,
         "UPDATE session SET status=?, ended_at=strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE id=?");
  s.Bind(1, status).Bind(2, session_id).Run();
}

std::vector<Session> Database::Sessions(std::int64_t participant_id) const {
  Stmt s(db_,
         "SELECT id, participant_id, started_at, coalesce(ended_at,''), status, software_version, "
         "device, calibration, provenance_json, plan_json, actuator, screens, rater FROM session "
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
    x.status = s.Text(4);
    x.software_version = s.Text(5);
    x.device = s.Text(6);
    x.calibration = s.Text(7);
    x.provenance_json = s.Text(8);
    x.plan_json = s.Text(9);
    x.actuator = s.Text(10);
    x.screens = s.Int(11) != 0;
    x.rater = s.Text(12);
    out.push_back(std::move(x));
  }
  return out;
}

namespace {
constexpr const char* kInsertTrial =
    "INSERT INTO trial(session_id, plan_index, phase, material, comparison, method, repetition, "
    "left_stimulus, right_stimulus, status, attempts) VALUES (?,?,?,?,?,?,?,?,?,?,?)";
void BindTrial(Stmt& s, const Trial& t) {
  s.Bind(1, t.session_id).Bind(2, t.plan_index).Bind(3, t.phase).Bind(4, t.material)
      .Bind(5, t.comparison).Bind(6, t.method).Bind(7, t.repetition).Bind(8, t.left)
      .Bind(9, t.right).Bind(10, t.status).Bind(11, t.attempts);
}
}  // namespace

std::int64_t Database::AddTrial(const Trial& t) {
  Stmt s(db_, kInsertTrial);
  BindTrial(s, t);
  s.Run();
  return sqlite3_last_insert_rowid(db_);
}

std::vector<std::int64_t> Database::AddTrials(const std::vector<Trial>& trials) {
  Transaction tx(db_);
  Stmt s(db_, kInsertTrial);
  std::vector<std::int64_t> ids;
  ids.reserve(trials.size());
  for (const auto& t : trials) {
    BindTrial(s, t);
    s.Run();
    s.Reset();
    ids.push_back(sqlite3_last_insert_rowid(db_));
  }
  tx.Commit();
  return ids;
}

int Database::StartTrial(std::int64_t trial_id) {
  Stmt s(db_,
         "UPDATE trial SET status='running', attempts=attempts+1, "
         "started_at=strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE id=? AND status<>'completed'");
  s.Bind(1, trial_id).Run();
  if (sqlite3_changes(db_) != 1)
    throw std::runtime_error(path_ + ": trial " + std::to_string(trial_id) +
                             " does not exist or is already completed");
  return CurrentAttempt(trial_id);
}

int Database::CurrentAttempt(std::int64_t trial_id) const {
  Stmt s(db_, "SELECT attempts FROM trial WHERE id=?");
  s.Bind(1, trial_id);
  if (!s.Step()) throw std::runtime_error(path_ + ": no trial " + std::to_string(trial_id));
  return static_cast<int>(s.Int(0));
}

void Database::SetTrialStatus(std::int64_t trial_id, const std::string& status) {
  Stmt s(db_, "UPDATE trial SET status=? WHERE id=?");
  s.Bind(1, status).Bind(2, trial_id).Run();
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
            "stream {}: {} samples queued, {} committed by the writer, {} stored{}", r.stream,
            kept, r.samples_written, in_db, r.error.empty() ? "" : " (" + r.error + ")"));
    }
    for (const auto& [n, c] : stored)
      if (std::find(reported.begin(), reported.end(), n) == reported.end())
        problems.push_back(fmt::format("stream {}: {} samples stored that no stream of attempt {} "
                                       "reported (another process wrote this trial)",
                                       n, c, attempt));
    if (!problems.empty())
      throw TrajectoryIncomplete(fmt::format("{}: trial {} attempt {}: trajectories not whole: {}",
                                             path_, trial_id, attempt, fmt::join(problems, "; ")));
    Stmt ins(db_,
             "INSERT INTO trajectory_stream(trial_id, attempt, stream, rate_hz, samples_offered, "
             "samples_dropped, samples_written) VALUES (?,?,?,?,?,?,?)");
    for (const auto& r : streams) {
      if (r.trial_id != trial_id || r.attempt != attempt) continue;
      ins.Bind(1, trial_id).Bind(2, attempt).Bind(3, r.stream).Bind(4, r.rate_hz)
          .Bind(5, static_cast<std::int64_t>(r.samples_offered))
          .Bind(6, static_cast<std::int64_t>(r.samples_dropped))
          .Bind(7, static_cast<std::int64_t>(r.samples_written));
      ins.Run();
      ins.Reset();
    }
  }
  // A rating without a source is the session's rater's.
  Stmt ins(db_,
           "INSERT INTO rating(trial_id, criterion, score, response_time_s, source) VALUES (?,?,?,?, "
           "coalesce(nullif(?,''), (SELECT s.rater FROM trial t JOIN session s ON s.id = t.session_id "
           "WHERE t.id = ?1)))");
  for (const auto& r : ratings) {
    ins.Bind(1, trial_id).Bind(2, r.criterion).Bind(3, r.score).Bind(4, r.response_time_s).Bind(5, r.source);
    ins.Run();
    ins.Reset();
  }
  // The completion marker commits with the ratings; a completed trial cannot be completed again.
  Stmt done(db_,
            "UPDATE trial SET status='completed', completed_attempt=attempts, "
            "completed_at=strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE id=? AND status<>'completed'");
  done.Bind(1, trial_id).Run();
  if (sqlite3_changes(db_) != 1)
    throw std::runtime_error(path_ + ": trial " + std::to_string(trial_id) +
                             " does not exist or is already completed; ratings not stored");
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
  while (s.Step()) out.push_back(ReadTrial(s));
  return out;
}

std::vector<Rating> Database::Ratings(std::int64_t trial_id) const {
  Stmt s(db_, "SELECT criterion, score, response_time_s, source FROM rating WHERE trial_id=? ORDER BY id");
  s.Bind(1, trial_id);
  std::vector<Rating> out;
  while (s.Step()) {
    // SQLite stores any type in a REAL column; text or NULL is damage, never a score of 0.
    for (int col : {1, 2})
      if (!s.IsNumber(col) || !std::isfinite(s.Real(col)))
        throw InputError(path_, 0, col == 1 ? "rating.score" : "rating.response_time_s",
                         fmt::format("trial {} criterion '{}': '{}' is not a finite number",
                                     trial_id, s.Text(0), s.IsNull(col) ? "NULL" : s.Text(col)));
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
  Stmt s(db_, "INSERT INTO event(session_id, trial_id, kind, detail) VALUES (?,?,?,?)");
  s.Bind(1, e.session_id);
  if (e.trial_id) s.Bind(2, *e.trial_id);
  else s.BindNull(2);
  s.Bind(3, e.kind).Bind(4, e.detail).Run();
  return sqlite3_last_insert_rowid(db_);
}

std::vector<Event> Database::Events(std::int64_t session_id) const {
  Stmt s(db_, "SELECT id, session_id, trial_id, kind, detail, created_at FROM event "
              "WHERE session_id=? ORDER BY id");
  s.Bind(1, session_id);
  std::vector<Event> out;
  while (s.Step()) {
    Event e{s.Int(0), s.Int(1), std::nullopt, s.Text(3), s.Text(4), s.Text(5)};
    if (!s.IsNull(2)) e.trial_id = s.Int(2);
    out.push_back(std::move(e));
  }
  return out;
}

std::int64_t Database::SaveMaterialModel(const std::string& name, const std::string& toml_text) {
  const std::string hash = HashText(toml_text);
  Stmt f(db_, "SELECT id FROM material_model WHERE name=? AND hash=?");
  f.Bind(1, name).Bind(2, hash);
  if (f.Step()) return f.Int(0);
  Stmt s(db_, "INSERT INTO material_model(name, hash, toml) VALUES (?,?,?)");
  s.Bind(1, name).Bind(2, hash).Bind(3, toml_text).Run();
  return sqlite3_last_insert_rowid(db_);
}

std::int64_t Database::SaveMeasurement(const std::string& material, const std::string& csv_text,
                                       const std::string& metadata_json) {
  Stmt s(db_, "INSERT INTO measurement(material, hash, csv, metadata_json) VALUES (?,?,?,?)");
  s.Bind(1, material).Bind(2, HashText(csv_text)).Bind(3, csv_text)
      .Bind(4, metadata_json.empty() ? std::string("{}") : metadata_json).Run();
  return sqlite3_last_insert_rowid(db_);
}

void Database::InsertTrajectoryChunk(const TrajectoryChunk& c) {
  HL_REQUIRE(c.attempt >= 0, "trajectory chunk attempt must not be negative");
  HL_REQUIRE(!c.channels.empty(), "trajectory chunk needs at least one channel");
  HL_REQUIRE(c.samples.size() % c.channels.size() == 0,
                  "trajectory chunk sample count is not a multiple of its channel count");
  HL_REQUIRE(c.rate_hz > 0, "trajectory chunk rate must be positive");
  Stmt s(db_,
         "INSERT INTO trajectory_chunk(trial_id, stream, start_time_s, rate_hz, channels, "
         "sample_count, samples, attempt) VALUES (?,?,?,?,?,?,?,?)");
  s.Bind(1, c.trial_id).Bind(2, c.stream).Bind(3, c.start_time_s).Bind(4, c.rate_hz)
      .Bind(5, JoinChannels(c.channels)).Bind(6, static_cast<std::int64_t>(c.sample_count()))
      .BindBlob(7, c.samples.data(), c.samples.size() * sizeof(float)).Bind(8, c.attempt).Run();
}

std::vector<TrajectoryChunk> Database::TrajectoryChunks(std::int64_t trial_id) const {
  Stmt a(db_, "SELECT coalesce(completed_attempt, attempts) FROM trial WHERE id=?");
  a.Bind(1, trial_id);
  if (!a.Step()) return {};
  return TrajectoryChunks(trial_id, static_cast<int>(a.Int(0)));
}

std::vector<TrajectoryChunk> Database::TrajectoryChunks(std::int64_t trial_id, int attempt) const {
  Stmt s(db_,
         "SELECT trial_id, stream, start_time_s, rate_hz, channels, sample_count, samples, attempt "
         "FROM trajectory_chunk WHERE trial_id=? AND attempt=? ORDER BY stream, start_time_s, id");
  s.Bind(1, trial_id).Bind(2, attempt);
  std::vector<TrajectoryChunk> out;
  while (s.Step()) {
    TrajectoryChunk c;
    c.trial_id = s.Int(0);
    c.stream = s.Text(1);
    c.start_time_s = s.Real(2);
    c.rate_hz = s.Real(3);
    c.channels = SplitChannels(s.Text(4));
    c.attempt = static_cast<int>(s.Int(7));
    const auto bytes = static_cast<std::size_t>(s.BlobBytes(6));
    // A blob that does not match its row's sample and channel counts is damage, not data.
    if (c.channels.empty() || s.Int(5) < 0 ||
        bytes != static_cast<std::size_t>(s.Int(5)) * c.channels.size() * sizeof(float))
      throw std::runtime_error(fmt::format(
          "{}: trajectory chunk of trial {} stream {} is damaged ({} bytes for {} samples of {} "
          "channels)", path_, trial_id, c.stream, bytes, s.Int(5), c.channels.size()));
    c.samples.resize(bytes / sizeof(float));
    if (bytes) std::memcpy(c.samples.data(), s.Blob(6), bytes);
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace hapticlab::db

namespace hapticlab::db {

WriterLease::WriterLease(const std::string& db_path) {
  fd_ = ::open(db_path.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw InputError(db_path, 0, "--db", std::string("cannot open: ") + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    std::string holder = "another process";
    if (err == EWOULDBLOCK) {
      try {
        Database d(db_path, {.create = false, .read_only = true, .busy_timeout_ms = 2000});
        Stmt q(d.handle(), "SELECT pid, host, since FROM writer_lease WHERE id = 1");
        if (q.Step())
          holder = fmt::format("process {} on host {} (since {})", q.Int(0), q.Text(1), q.Text(2));
      } catch (const std::exception&) {
        // An older schema or a database being created: the generic message stands.
      }
      throw InputError(db_path, 0, "--db",
                       holder + " is writing this study database; one writer at a time: wait "
                       "for it to finish, or stop it, then resume");
    }
    throw InputError(db_path, 0, "--db", std::string("cannot lock: ") + std::strerror(err));
  }
  // Name the holder for the next one who tries.
  try {
    Database d(db_path);
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) std::strcpy(host, "unknown");
    Stmt s(d.handle(), "INSERT OR REPLACE INTO writer_lease(id, pid, host) VALUES (1, ?, ?)");
    s.Bind(1, static_cast<std::int64_t>(::getpid())).Bind(2, std::string(host)).Run();
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

WriterLease::~WriterLease() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace hapticlab::db
