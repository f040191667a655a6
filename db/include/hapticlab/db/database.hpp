#pragma once
/// @file The study record in SQLite (docs/formats.md): typed access to every table.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticlab/core/enum_names.hpp"
#include "hapticlab/core/phase_kind.hpp"
#include "hapticlab/db/event_kind.hpp"

struct sqlite3;

namespace hapticlab::db {

/// Latest schema version this build writes. Older files are migrated forward on open.
inline constexpr int kSchemaVersion = 10;

/// Site code of a session recorded without `--site` (and of every session before schema v10).
inline constexpr const char* kDefaultSiteCode = "L0";

/// A study: one protocol, its text and hash, and the study seed.
struct Study {
  std::int64_t id = 0;
  std::string name;
  std::string protocol_toml;  ///< the protocol file exactly as run
  std::string protocol_hash;  ///< hex digest of protocol_toml
  std::uint64_t seed = 0;     ///< study seed; participants derive theirs from it
  /// Hex SHA-256 of the protocol's canonical form (protocols/canonical.hpp), the protocol's
  /// identity (schema v7; empty in a study recorded before it until the runner fills it in).
  std::string protocol_canonical_sha256;
};

/// A participant, known only by a pseudonymous code.
struct Participant {
  std::int64_t id = 0;
  std::int64_t study_id = 0;
  std::string code;        ///< pseudonymous, e.g. "P07"; see IsPseudonymousCode
  int index = 0;           ///< participant index used for planning (0-based)
  std::uint64_t seed = 0;  ///< per-participant seed used for planning and simulation
};

/// Rating source of the simulated observer (anything else is a person's input device).
inline constexpr const char* kRaterSimulated = "simulated";

/// A session's status; the session table's `status` holds its name (kSessionStatusNames).
enum class SessionStatus {
  kRunning,    ///< started, not ended (or its process died: `study resume` continues it)
  kCompleted,  ///< every planned trial completed
  kAborted,    ///< stopped by the experimenter, a signal or --stop-after (resumable)
  kFailed,     ///< stopped on an error (a 'stopped' event says why; resumable)
};
inline constexpr EnumTable<SessionStatus, 4> kSessionStatusNames{
    {{SessionStatus::kRunning, "running"},
     {SessionStatus::kCompleted, "completed"},
     {SessionStatus::kAborted, "aborted"},
     {SessionStatus::kFailed, "failed"}}};

/// One sitting of a participant, with the provenance needed to reproduce it.
struct Session {
  std::int64_t id = 0;
  std::int64_t participant_id = 0;
  std::string started_at;  ///< ISO-8601 UTC, filled by the database when empty
  std::string ended_at;    ///< empty while running
  SessionStatus status = SessionStatus::kRunning;
  std::string software_version;  ///< "<version>+<git sha>"
  std::string device;            ///< device back-end name and serial
  std::string calibration;       ///< device calibration description or hash
  std::string provenance_json;   ///< protocol hash, seeds, model hashes (JSON object)
  std::string plan_json;         ///< the resolved trial plan (schema v3)
  // The session's mode (schema v5); `study resume` continues in it.
  std::string actuator;  ///< vibrotactile actuator: "audio", "none" ("unrecorded": before v5)
  bool screens = false;  ///< participant window and console (--ui)
  std::string rater = kRaterSimulated;  ///< who rates: "simulated" or the participant's input
                                        ///< device ("window", "rating-box:VID:PID")
  /// The site that recorded it (schema v9): a short pseudonymous code (IsSiteCode).
  std::string site_code = kDefaultSiteCode;
};

/// A trial's status; the trial table's `status` holds its name (kTrialStatusNames).
enum class TrialStatus {
  kPlanned,    ///< not started
  kRunning,    ///< an attempt started and did not end (a crash: run again on resume)
  kCompleted,  ///< rated (its ratings and completion committed together)
  kFaulted,    ///< an attempt faulted; re-queued at the end of its phase
  kAborted,    ///< the session stopped during it
};
inline constexpr EnumTable<TrialStatus, 5> kTrialStatusNames{
    {{TrialStatus::kPlanned, "planned"},
     {TrialStatus::kRunning, "running"},
     {TrialStatus::kCompleted, "completed"},
     {TrialStatus::kFaulted, "faulted"},
     {TrialStatus::kAborted, "aborted"}}};

/// One trial of a session's plan.
struct Trial {
  std::int64_t id = 0;
  std::int64_t session_id = 0;
  int plan_index = 0;                  ///< position in the resolved plan (0-based)
  PhaseKind phase = PhaseKind::kMain;  ///< stored by name (kPhaseKindNames)
  std::string material;                ///< material shown (real sample id / virtual model)
  std::string comparison;              ///< the other stimulus: "virtual" or a material (reference)
  std::string method;                  ///< rendering method name; empty for real-real pairs
  int repetition = 0;                  ///< 0-based repetition index
  std::string left;                    ///< stimulus on the left square
  std::string right;                   ///< stimulus on the right square
  TrialStatus status = TrialStatus::kPlanned;
  int attempts = 0;           ///< how many times the trial was started
  int completed_attempt = 0;  ///< the attempt whose data the trial holds (0 until completed)
};

/// One rating of one criterion in one trial.
struct Rating {
  std::string criterion;       ///< e.g. "roughness"
  double score = 0;            ///< on the protocol's scale (0-100 by default)
  double response_time_s = 0;  ///< from stimulus end to confirmation [s]
  /// Who gave it: "simulated" (the simulated observer) or the participant's input device
  /// ("window", "rating-box:VID:PID"). Empty when stored: the session's rater.
  std::string source;
};

/// An event in a session: break, pause, abort, device fault, trial re-queue... (the audit
/// trail: docs/studies.md).
struct Event {
  std::int64_t id = 0;
  std::int64_t session_id = 0;
  std::optional<std::int64_t> trial_id;
  EventKind kind =
      EventKind::kUnnamed;  ///< stored by name (kEventKindNames); LogEvent refuses kUnnamed
  std::string detail;
  std::string created_at;
  /// Who or what established the fact the event states (schema v7), e.g.
  /// "experimenter:E01", "participant", "hapticlab:runner", "device:falcon",
  /// "simulation:inject-faults", "os:signal" (runner/audit.hpp). Empty when stored:
  /// "hapticlab".
  std::string established_by;
};

/// A chunk of a trajectory stream: samples at a constant rate, packed float32 row-major
/// (sample-major: samples[i * channels.size() + c]).
struct TrajectoryChunk {
  std::int64_t trial_id = 0;
  std::string stream;                 ///< e.g. "force", "vibration"
  double start_time_s = 0;            ///< time of the first sample [s]
  double rate_hz = 0;                 ///< sample rate [Hz]
  std::vector<std::string> channels;  ///< channel names with units, e.g. "fx_N"
  std::vector<float> samples;
  int attempt = 0;  ///< the trial's attempt that recorded it (1-based; 0: before
                    ///< the trial was started, or unattributed by migration)
  std::size_t sample_count() const {
    return channels.empty() ? 0 : samples.size() / channels.size();
  }
};

/// What one trajectory stream of one trial attempt delivered, as the writer counted it.
/// Whole when samples_written == samples_offered - samples_dropped and no error is left.
struct StreamReport {
  std::int64_t trial_id = 0;
  int attempt = 0;
  std::string stream;
  double rate_hz = 0;                 ///< [Hz]
  std::uint64_t samples_offered = 0;  ///< Push calls by the producer
  std::uint64_t samples_dropped = 0;  ///< refused because the queue was full (time gaps)
  std::uint64_t samples_written = 0;  ///< committed to the database
  std::string error;                  ///< first write error met by this stream ("" when none)
};

/// Thrown by CompleteTrial when a trial's trajectories are not whole: the trial is not
/// completed (nothing of the completion is stored) and the caller faults and re-queues it.
class TrajectoryIncomplete : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// True when `code` is a pseudonymous participant code (core/participant_code.hpp: 1-32
/// letters, digits, '-' or '_' with a digit, no name-, date-, phone- or e-mail-like shape).
bool IsPseudonymousCode(const std::string& code);

/// Empty when `code` is a site code: a pseudonymous code (IsPseudonymousCode) of at most 8
/// characters (e.g. "L0", "S02"; never a lab's or a town's name); else why it is not.
std::string SiteCodeProblem(const std::string& code);

/// Options for opening a database.
struct OpenOptions {
  bool create = true;               ///< create the file when missing
  int migrate_to = kSchemaVersion;  ///< migrate up to this version (tests use older ones)
  bool read_only = false;
  int busy_timeout_ms = 10000;  ///< wait for another writer this long
};

/// A connection to a study record. Not thread-safe: one per thread.
class Database {
 public:
  /// Opens (and creates/migrates) the file. Throws std::runtime_error naming the file when
  /// it is not a HapticLab database or is newer than this build.
  explicit Database(const std::string& path, const OpenOptions& options = {});
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;

  const std::string& path() const { return path_; }
  /// Schema version stored in the file.
  int SchemaVersion() const;
  /// Applies forward migrations up to `target`, all in one write transaction (a second
  /// process opening the same file waits for it, then finds nothing to do).
  void Migrate(int target = kSchemaVersion);
  /// "ok" when SQLite's integrity check passes, else its report.
  std::string IntegrityCheck() const;

  // Studies and participants.
  std::int64_t CreateStudy(const Study& s);
  std::optional<Study> FindStudy(const std::string& name) const;
  std::vector<Study> Studies() const;
  /// Records the canonical hash of a study recorded before schema v7.
  void SetStudyCanonicalHash(std::int64_t study_id, const std::string& sha256);
  std::int64_t AddParticipant(const Participant& p);
  std::optional<Participant> FindParticipant(std::int64_t study_id, const std::string& code) const;
  std::vector<Participant> Participants(std::int64_t study_id) const;
  /// True when the participant has no session yet: a code reserved by `participant new`.
  bool IsReserved(std::int64_t participant_id) const;

  // Sessions.
  std::int64_t StartSession(const Session& s);
  void EndSession(std::int64_t session_id, SessionStatus status);
  /// Marks an ended (or killed) session running again for `study resume` (ended_at cleared).
  void ReopenSession(std::int64_t session_id);
  /// Records a new mode for a session (resume with --change-mode); ratings stored from now
  /// on carry the new rater as their source.
  void SetSessionMode(std::int64_t session_id, const std::string& device,
                      const std::string& actuator, bool screens, const std::string& rater);
  /// Copies the database's committed content (the -wal included) into `dest` with SQLite's
  /// online backup API, while other connections may keep writing. `dest` must not exist.
  /// @throws InputError naming dest when it exists or cannot be written
  void Backup(const std::string& dest) const;
  /// Moves every committed page from the -wal into the main file and empties the -wal
  /// (PRAGMA wal_checkpoint(TRUNCATE)), so the main file alone holds the record. Returns
  /// false when another connection kept the checkpoint from completing.
  bool Checkpoint();
  std::vector<Session> Sessions(std::int64_t participant_id) const;

  // Trials and ratings.
  std::int64_t AddTrial(const Trial& t);
  /// Marks a trial running and counts the attempt. Returns the attempt number (1-based);
  /// trajectory streams opened for the trial from now on are tagged with it.
  int StartTrial(std::int64_t trial_id);
  /// The trial's current attempt (its attempts counter; 0 before it was started).
  int CurrentAttempt(std::int64_t trial_id) const;
  void SetTrialStatus(std::int64_t trial_id, TrialStatus status);
  /// Stores every rating of the trial and marks it completed, in one transaction: after a
  /// crash either all of them and the completion marker are present, or none.
  /// The trial's current attempt becomes its completing attempt. `streams` are the writer's
  /// reports of the trial's streams (TrajectoryWriter::TakeReports); for each report of the
  /// current attempt the check (offered - dropped == written == samples stored in chunks) is
  /// verified and stored in `trajectory_stream`, and the attempt must hold no chunks of any
  /// other stream. With no reports (nothing recorded) no trajectory check is made.
  /// @throws TrajectoryIncomplete (and stores nothing) when a stream is not whole
  void CompleteTrial(std::int64_t trial_id, const std::vector<Rating>& ratings,
                     const std::vector<StreamReport>& streams = {});
  /// The stored sample-count checks of a trial's completing attempt.
  std::vector<StreamReport> StreamChecks(std::int64_t trial_id) const;
  std::vector<Trial> Trials(std::int64_t session_id) const;
  std::vector<Rating> Ratings(std::int64_t trial_id) const;
  /// Rated trials of a session in the order their ratings were committed.
  std::vector<std::int64_t> RatedTrialsInCompletionOrder(std::int64_t session_id) const;

  // Events, models, trajectories.
  std::int64_t LogEvent(const Event& e);
  std::vector<Event> Events(std::int64_t session_id) const;
  std::int64_t SaveMaterialModel(const std::string& name, const std::string& toml_text);
  void InsertTrajectoryChunk(const TrajectoryChunk& c);
  /// Chunks of the trial's completing attempt when it is completed, else of its current
  /// attempt (possibly partial). Chunks of other attempts are never mixed in.
  std::vector<TrajectoryChunk> TrajectoryChunks(std::int64_t trial_id) const;
  /// Chunks of one attempt of a trial.
  std::vector<TrajectoryChunk> TrajectoryChunks(std::int64_t trial_id, int attempt) const;
  /// "ok" when SQLite's quick_check passes, else its report (cheaper than IntegrityCheck).
  std::string QuickCheck() const;
  /// Every completed trial's completing attempt against its stored sample-count checks:
  /// each checked stream's chunks hold exactly the samples written at completion, and no
  /// other stream has chunks in that attempt. Returns one line per problem (empty: whole).
  /// Exports call it before reading trajectories.
  std::vector<std::string> VerifyTrajectories() const;

  /// Raw handle for module-internal use (export, writer).
  sqlite3* handle() const { return db_; }
  /// Runs SQL with no result rows; throws std::runtime_error with SQLite's message.
  void Exec(const std::string& sql) const;

 private:
  /// Every table and column of the current schema is present (extra ones are allowed).
  /// @throws InputError naming the file and the first one missing.
  void CheckShape() const;

  std::string path_;
  sqlite3* db_ = nullptr;
};

/// A write transaction on a Database (RAII): BEGIN IMMEDIATE when made, so the write lock is
/// taken at once (another writer waits up to the busy timeout, then this throws
/// std::runtime_error naming the file); what is written through the connection until Commit()
/// is stored together. Destroyed without a successful Commit() (an exception on the way, a
/// COMMIT that failed) it rolls back: after a crash or an error all of it or none is stored.
/// Transactions do not nest: a Database method that keeps its own (CompleteTrial, Migrate)
/// cannot run inside one.
///
///   db::WriteTransaction tx(database);
///   database.LogEvent(...);
///   database.EndSession(...);
///   tx.Commit();
class WriteTransaction {
 public:
  explicit WriteTransaction(Database& database);
  ~WriteTransaction();
  WriteTransaction(const WriteTransaction&) = delete;
  WriteTransaction& operator=(const WriteTransaction&) = delete;
  /// COMMIT. @throws std::runtime_error naming the file when it fails (then nothing is stored)
  void Commit();

 protected:
  /// On a bare connection (the module's own connections without a Database).
  explicit WriteTransaction(sqlite3* db);

 private:
  sqlite3* db_;
  bool done_ = false;
};

/// The one-writer lease of a study database: an advisory lock (flock) on the database file,
/// held for the object's life, plus a `writer_lease` row naming the process id and host so
/// a second writer is told who holds it; the row is deleted when the lease ends (a killed
/// process leaves it, and the next writer replaces it). The lock is released by the kernel when the
/// process ends, even on SIGKILL. Take it before opening any Database on the file and release it
/// after every connection of this process to the file is closed (so closing its descriptor
/// cannot drop SQLite's own locks).
class WriterLease {
 public:
  /// Creates the file when missing (an empty file is a new database).
  /// @throws InputError naming the file and the holder when another process holds the lease
  explicit WriterLease(const std::string& db_path);
  ~WriterLease();
  WriterLease(const WriterLease&) = delete;
  WriterLease& operator=(const WriterLease&) = delete;

 private:
  std::string path_;
  int fd_ = -1;
};

/// Opens a study database for reading after checking it: the file exists and SQLite's
/// quick_check passes. For analysis and export, which must never run on a damaged record.
/// A file of an older schema is migrated forward first (which writes to it).
/// @throws InputError naming the file (exit 2) when it is missing, not a HapticLab database,
///         newer than this build, or damaged
Database OpenForReading(const std::string& path);

/// Hex SHA-256 digest of a text (OpenSSL), for provenance of protocols and models.
std::string HashText(const std::string& text);

}  // namespace hapticlab::db
