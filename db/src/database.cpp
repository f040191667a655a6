// Database: opening (file mode, WAL), schema migration, integrity checks, backup; WriterLease.
#include "hapticlab/db/database.hpp"

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
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/participant_code.hpp"
#include "hapticlab/core/status.hpp"
#include "schema.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::ExecSql;
using internal::Stmt;
using internal::Transaction;

bool IsPseudonymousCode(const std::string& code) { return PseudonymousCodeProblem(code).empty(); }

std::string SiteCodeProblem(const std::string& code) {
  if (code.size() > 8) return "a site code has at most 8 characters";
  return PseudonymousCodeProblem(code);
}

Database OpenForReading(const std::string& path) {
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode))
    throw InputError(path, 0, "db", "a folder, not a study database file");
  if (!exists || !S_ISREG(st.st_mode)) throw InputError(path, 0, "db", "no such database file");
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
                   "from a backup; details: " +
                       report);
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
  if (::stat(wal.c_str(), &ws) == 0 &&
      ((ws.st_mode & 0222) == 0 || ::access(wal.c_str(), W_OK) != 0))
    throw InputError(
        wal, 0, "db",
        "the database's write-ahead log is read-only; make it (and the -shm file) "
        "writable: it may hold committed trials that are not yet in the database file");
  const std::string shm = path + "-shm";
  struct stat st {};
  if (::stat(shm.c_str(), &st) != 0) return;  // none: SQLite creates it
  if ((st.st_mode & 0222) == 0 || ::access(shm.c_str(), W_OK) != 0)
    throw InputError(shm, 0, "db",
                     "the database's shared-memory file is read-only; make it writable (and the "
                     "-wal file) or, when no HapticLab process uses the database, delete it");
  // A connection opening the database at the same time grows the file a 4 KiB page at a
  // time up to a whole 32 KiB region, so a size between regions can be a moment of that:
  // only a size that stays between regions for 100 ms is a truncated file.
  for (int i = 0; st.st_size % 32768 != 0 && i < 20; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (::stat(shm.c_str(), &st) != 0) return;
  }
  if (st.st_size % 32768 != 0)
    throw InputError(shm, 0, "db",
                     "the database's shared-memory file is truncated (" +
                         std::to_string(st.st_size) +
                         " bytes); when no HapticLab process uses the database, delete it");
}

// SQLite does not call the busy handler while it changes the journal mode: when several
// processes open one new file at once, all but one get SQLITE_BUSY at once. Retried here
// for as long as the busy timeout allows.
void EnterWalMode(sqlite3* db, int busy_timeout_ms) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(busy_timeout_ms);
  for (;;) {
    const int rc = sqlite3_exec(db, "PRAGMA journal_mode = WAL", nullptr, nullptr, nullptr);
    if (rc == SQLITE_OK) return;
    if ((rc & 0xff) != SQLITE_BUSY || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ExecSql(db, "PRAGMA journal_mode = WAL");  // once more, for its error message
}

}  // namespace

namespace {

// Refuses a file that is not a SQLite database (a protocol given as --db, say), naming it as
// such rather than as damaged. Only bytes that differ from SQLite's 16-byte header count: a
// file another process is creating reads as zeros or as a part of the header, and is left to
// SQLite's own locking.
void RefuseAnotherKindOfFile(const std::string& path) {
  constexpr char kHeader[] = "SQLite format 3";  // and its terminating NUL: 16 bytes
  char head[sizeof kHeader] = {};
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;  // missing or unreadable: SQLite reports it
  const ssize_t n = ::read(fd, head, sizeof head);
  ::close(fd);
  for (ssize_t i = 0; i < n; ++i)
    if (head[i] != '\0' && head[i] != kHeader[i])
      throw InputError(path, 0, "db",
                       "not a SQLite database (it does not start with SQLite's file header): "
                       "expected the study database that 'study run' writes");
}

}  // namespace

Database::Database(const std::string& path, const OpenOptions& options) : path_(path) {
  if (path != ":memory:") RefuseAnotherKindOfFile(path);
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
      if (options.migrate_to == kSchemaVersion && path != ":memory:") CheckShape();
    } else {
      const int v = SchemaVersion();
      if (v > kSchemaVersion)
        throw std::runtime_error(path + ": schema version " + std::to_string(v) +
                                 " is newer than this build supports (" +
                                 std::to_string(kSchemaVersion) + ")");
      if (v == kSchemaVersion) CheckShape();
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
Database::Database(Database&& o) noexcept
    : path_(std::move(o.path_)), db_(std::exchange(o.db_, nullptr)) {}
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
      throw InputError(path_, 0, "db",
                       "not a HapticLab study database (an SQLite file without its "
                       "schema_version table)");
    return 0;
  }
  Stmt v(db_, "SELECT max(version) FROM schema_version");
  return v.Step() && !v.IsNull(0) ? static_cast<int>(v.Int(0)) : 0;
}

void Database::Migrate(int target) {
  HL_REQUIRE(target >= 0 && target <= kSchemaVersion,
             "schema version " + std::to_string(target) + " does not exist");
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
    try {
      ExecSql(db_, internal::MigrationSql(k));
    } catch (const std::runtime_error&) {
      // SQLITE_ERROR here: a table or column the migration adds is there already, or one it
      // changes is missing: the file's tables do not match its recorded version.
      if ((sqlite3_errcode(db_) & 0xff) != SQLITE_ERROR) throw;  // I/O, a full disk, ...
      throw InputError(path_, 0, "db",
                       fmt::format("the file says schema version {}, but its tables do not match "
                                   "it (migration to version {} failed: {}): it was changed "
                                   "outside HapticLab; restore it from a backup",
                                   current, k, sqlite3_errmsg(db_)));
    }
    Stmt ins(db_, "INSERT INTO schema_version(version) VALUES (?)");
    ins.Bind(1, k).Run();
  }
  tx.Commit();
}

namespace {

using TableShape = std::map<std::string, std::set<std::string>>;  // table -> its columns

TableShape ShapeOf(sqlite3* db) {
  TableShape shape;
  Stmt t(db, "SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name");
  while (t.Step()) shape[t.Text(0)];
  for (auto& [table, columns] : shape) {
    // pragma_table_info takes the table's name as a bound value: no SQL is built from names.
    Stmt c(db, "SELECT name FROM pragma_table_info(?)");
    c.Bind(1, table);
    while (c.Step()) columns.insert(c.Text(0));
  }
  return shape;
}

// The tables and columns of the current schema, from a fresh in-memory database (once).
const TableShape& ExpectedShape() {
  static const TableShape kShape = [] {
    const Database fresh(":memory:");
    return ShapeOf(fresh.handle());
  }();
  return kShape;
}

}  // namespace

void Database::CheckShape() const {
  const TableShape have = ShapeOf(db_);
  for (const auto& [table, columns] : ExpectedShape()) {
    const auto t = have.find(table);
    std::string missing = t == have.end() ? "table '" + table + "'" : "";
    if (missing.empty())
      for (const auto& c : columns)
        if (!t->second.count(c)) {
          missing = "column '" + c + "' of table '" + table + "'";
          break;
        }
    if (!missing.empty())
      throw InputError(path_, 0, "db",
                       "not a HapticLab study database of schema version " +
                           std::to_string(kSchemaVersion) + " (" + missing +
                           " is missing): it was changed outside HapticLab, or is another "
                           "program's file; restore it from a backup");
  }
}

std::string Database::QuickCheck() const {
  Stmt s(db_, "PRAGMA quick_check");
  std::string out;
  while (s.Step()) out += (out.empty() ? "" : "\n") + s.Text(0);
  return out;
}

std::vector<std::string> Database::VerifyTrajectories() const {
  // Trials named as people know them: participant code and plan number, not the row id.
  constexpr const char* kWho =
      " JOIN session se ON se.id = t.session_id JOIN participant p ON p.id = se.participant_id ";
  std::vector<std::string> out;
  {
    Stmt q(db_,
           (std::string("SELECT t.plan_index + 1, s.stream, s.samples_written, (SELECT "
                        "coalesce(sum(c.sample_count), 0) FROM trajectory_chunk c WHERE c.trial_id "
                        "= t.id AND c.attempt = t.completed_attempt AND c.stream = s.stream), "
                        "p.code FROM trial t JOIN trajectory_stream s ON s.trial_id = t.id AND "
                        "s.attempt = t.completed_attempt") +
            kWho + "WHERE t.status = 'completed' ORDER BY t.id, s.stream")
               .c_str());
    while (q.Step())
      if (q.Int(2) != q.Int(3))
        out.push_back(
            fmt::format("participant {} trial {} stream {}: {} samples stored, {} at completion",
                        q.Text(4), q.Int(0), q.Text(1), q.Int(3), q.Int(2)));
  }
  Stmt q(db_,
         (std::string("SELECT t.plan_index + 1, c.stream, sum(c.sample_count), p.code FROM "
                      "trajectory_chunk c JOIN trial t ON t.id = c.trial_id AND c.attempt = "
                      "t.completed_attempt") +
          kWho +
          "WHERE t.status = 'completed' AND EXISTS (SELECT 1 FROM trajectory_stream s WHERE "
          "s.trial_id = t.id AND s.attempt = t.completed_attempt) AND NOT EXISTS (SELECT 1 "
          "FROM trajectory_stream s WHERE s.trial_id = t.id AND s.attempt = "
          "t.completed_attempt AND s.stream = c.stream) GROUP BY c.trial_id, c.stream ORDER BY "
          "c.trial_id, c.stream")
             .c_str());
  while (q.Step())
    out.push_back(
        fmt::format("participant {} trial {} stream {}: {} samples stored that no "
                    "check covers",
                    q.Text(3), q.Int(0), q.Text(1), q.Int(2)));
  return out;
}

std::string Database::IntegrityCheck() const {
  Stmt s(db_, "PRAGMA integrity_check");
  std::string out;
  while (s.Step()) out += (out.empty() ? "" : "\n") + s.Text(0);
  return out;
}

void Database::Backup(const std::string& dest) const {
  // Refuse to overwrite: a backup over an older record (or the source) would lose it.
  struct ::stat st {};
  if (::stat(dest.c_str(), &st) == 0)
    throw InputError(dest, 0, "DEST", "already exists; a backup never overwrites a file");
  const std::filesystem::path parent = std::filesystem::path(dest).parent_path();
  const std::string folder = parent.empty() ? std::string(".") : parent.string();
  if (::stat(folder.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw InputError(dest, 0, "DEST", "its folder " + folder + " does not exist");
  sqlite3* out = nullptr;
  if (sqlite3_open_v2(dest.c_str(), &out, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
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
  const int rc = sqlite3_wal_checkpoint_v2(db_, "main", SQLITE_CHECKPOINT_TRUNCATE, &log_frames,
                                           &checkpointed);
  return rc == SQLITE_OK;
}

}  // namespace hapticlab::db

namespace hapticlab::db {

WriterLease::WriterLease(const std::string& db_path) : path_(db_path) {
  fd_ = ::open(db_path.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw InputError(db_path, 0, "db", std::string("cannot open: ") + std::strerror(errno));
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
      throw InputError(db_path, 0, "db",
                       holder +
                           " is writing this study database; one writer at a time: wait "
                           "for it to finish, or stop it, then resume");
    }
    throw InputError(db_path, 0, "db", std::string("cannot lock: ") + std::strerror(err));
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
  if (fd_ < 0) return;
  // The lease ends with its holder: no host name or process id stays in the file. (Every
  // other connection of this process to the file is closed by now; see the class comment.)
  try {
    Database d(path_, {.create = false, .busy_timeout_ms = 2000});
    ExecSql(d.handle(), "DELETE FROM writer_lease");
  } catch (...) {  // never throw from a destructor; a full disk may refuse even this
  }
  ::close(fd_);  // releases the flock
}

}  // namespace hapticlab::db
