// Fault injection on the study record: a full disk (a size-limited file), a lock held by
// another process, SIGKILL while trajectories are written, a read-only or truncated -shm,
// two writers and two schema creators at once. Each ends with every completed trial whole
// (ratings and every stream's samples), nothing duplicated or mixed, integrity ok.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::fault_test {
namespace {

constexpr double kRate = 1000;            // stream rate [Hz]
constexpr std::uint64_t kSamples = 3000;  // per stream and attempt (3 s at 1 kHz)
constexpr int kChannels = 4;
const std::vector<std::string> kStreams = {"left_force", "right_force"};

std::int64_t MakeSession(Database& db) {
  return test::AddStudySession(db, {.name = "fault", .protocol_toml = "x", .seed = 1}).session;
}

// One attempt of a trial as the runner makes it: start, record every stream, complete with
// the writer's reports. Returns true when the trial completed; false when its trajectories
// were not whole (the trial is then marked faulted, as the runner does).
bool RunAttempt(Database& db, TrajectoryWriter& w, std::int64_t trial) {
  const int attempt = db.StartTrial(trial);
  for (const auto& name : kStreams) {
    auto* s = w.OpenStream(trial, name, kRate, {"x_m", "y_m", "z_m", "fz_N"});
    EXPECT_EQ(s->attempt(), attempt);
    float v[kChannels];
    for (std::uint64_t i = 0; i < kSamples; ++i) {
      // The values identify trial, attempt and sample, so mixing would show.
      v[0] = static_cast<float>(trial);
      v[1] = static_cast<float>(attempt);
      v[2] = static_cast<float>(i);
      v[3] = 1;
      while (!s->Push(static_cast<double>(i) / kRate, v)) w.Flush();
    }
    w.CloseStream(s);
  }
  try {
    db.CompleteTrial(trial, {{"roughness", 50, 1}}, w.TakeReports(trial));
    return true;
  } catch (const TrajectoryIncomplete&) {
    db.SetTrialStatus(trial, TrialStatus::kFaulted);
    return false;
  }
}

// Every completed trial holds its ratings and exactly its completing attempt's samples.
void ExpectWhole(const std::string& path, std::int64_t session, int planned) {
  Database db(path);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
  EXPECT_TRUE(db.VerifyTrajectories().empty());
  const auto trials = db.Trials(session);
  ASSERT_EQ(static_cast<int>(trials.size()), planned);
  for (const auto& t : trials) {
    ASSERT_EQ(t.status, TrialStatus::kCompleted) << "trial " << t.id;
    EXPECT_EQ(db.Ratings(t.id).size(), 1u) << "trial " << t.id;
    EXPECT_EQ(t.completed_attempt, t.attempts);
    std::map<std::string, std::uint64_t> n;
    for (const auto& c : db.TrajectoryChunks(t.id)) {
      ASSERT_EQ(c.attempt, t.completed_attempt);
      n[c.stream] += c.sample_count();
      for (std::size_t i = 0; i < c.sample_count(); ++i) {
        ASSERT_EQ(c.samples[i * kChannels + 0], static_cast<float>(t.id));
        ASSERT_EQ(c.samples[i * kChannels + 1], static_cast<float>(t.completed_attempt));
        // Sample k sits at time k / rate.
        ASSERT_EQ(c.samples[i * kChannels + 2],
                  static_cast<float>(
                      std::llround((c.start_time_s + static_cast<double>(i) / kRate) * kRate)));
      }
    }
    for (const auto& s : kStreams) EXPECT_EQ(n[s], kSamples) << "trial " << t.id << " " << s;
    EXPECT_EQ(n.size(), kStreams.size());
    EXPECT_EQ(db.StreamChecks(t.id).size(), kStreams.size());
  }
}

std::vector<std::int64_t> Plan(Database& db, std::int64_t session, int n, int first_index = 0) {
  std::vector<Trial> t;
  for (int i = first_index; i < first_index + n; ++i)
    t.push_back(
        {.session_id = session, .plan_index = i, .phase = PhaseKind::kMain, .material = "m"});
  return test::AddTrials(db, t);
}

// Runs every trial not yet completed, in plan order, until all are (the resume).
void Resume(const std::string& path, std::int64_t session) {
  Database db(path);
  TrajectoryWriter w(path);
  for (const auto& t : db.Trials(session))
    if (t.status != TrialStatus::kCompleted) {
      ASSERT_TRUE(RunAttempt(db, w, t.id)) << "trial " << t.id;
    }
}

TEST(Fault, FullDiskFaultsTrialsAndResumeCompletesThemWhole) {
  test::TempDir dir;
  const std::string path = dir.File("full.db");
  std::int64_t session = 0;
  {
    Database db(path);
    session = MakeSession(db);
    Plan(db, session, 8);
  }
  const auto size = std::filesystem::file_size(path);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // The child's files may not grow past ~3 trials' worth: writes fail with EFBIG, as on a
    // full disk.
    signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{size + 200 * 1024, size + 200 * 1024};
    setrlimit(RLIMIT_FSIZE, &lim);
    int rc = 0;
    try {
      Database db(path);
      TrajectoryWriter w(path);
      int faults = 0;
      for (const auto& t : db.Trials(session)) faults += !RunAttempt(db, w, t.id);
      rc = faults > 0 ? 10 : 0;
    } catch (const std::exception&) {
      rc = 11;  // the database itself refused a write: the run stops with an error
    }
    _exit(rc);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_NE(WEXITSTATUS(status), 0) << "the size limit never bit: the test tests nothing";
  {
    Database db(path);
    int completed = 0;
    for (const auto& t : db.Trials(session)) completed += t.status == TrialStatus::kCompleted;
    EXPECT_LT(completed, 8);
    EXPECT_TRUE(db.VerifyTrajectories().empty());
  }
  Resume(path, session);  // space freed
  ExpectWhole(path, session, 8);
}

TEST(Fault, LockHeldByAnotherProcessFaultsTheAttemptNotTheData) {
  test::TempDir dir;
  const std::string path = dir.File("lock.db");
  std::int64_t session = 0;
  std::vector<std::int64_t> ids;
  {
    Database db(path);
    session = MakeSession(db);
    ids = Plan(db, session, 2);
  }
  int to_child[2], to_parent[2];
  ASSERT_EQ(pipe(to_child), 0);
  ASSERT_EQ(pipe(to_parent), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Holds the write lock until the parent says so.
    Database db(path);
    db.Exec("BEGIN EXCLUSIVE");
    char c = 1;
    if (write(to_parent[1], &c, 1) != 1) _exit(3);
    if (read(to_child[0], &c, 1) != 1) _exit(4);
    db.Exec("COMMIT");
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(to_parent[0], &c, 1), 1);
  {
    Database db(path, {.busy_timeout_ms = 30000});
    // The writer gives up on a commit after 50 ms; the streams close while the lock is held.
    TrajectoryWriter w(path, {.busy_timeout_ms = 50});
    auto* s = w.OpenStream(ids[0], "left_force", kRate, {"a"});
    const float v = 1;
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(s->Push(i / kRate, &v));
    const auto rep = w.CloseStream(s);
    EXPECT_LT(rep.samples_written, rep.samples_offered);
    EXPECT_FALSE(rep.error.empty());
    ASSERT_EQ(write(to_child[1], &c, 1), 1);  // release the lock
    int status = 0;
    waitpid(pid, &status, 0);
    // Completing with the incomplete report is refused and stores nothing.
    EXPECT_THROW(db.CompleteTrial(ids[0], {{"roughness", 50, 1}}, w.TakeReports(ids[0])),
                 TrajectoryIncomplete);
    EXPECT_TRUE(db.Ratings(ids[0]).empty());
    db.SetTrialStatus(ids[0], TrialStatus::kFaulted);
  }
  Resume(path, session);
  ExpectWhole(path, session, 2);
}

// Child: runs the plan's trials until killed.
[[noreturn]] void RunUntilKilled(const std::string& path, std::int64_t session) {
  try {
    Database db(path);
    TrajectoryWriter w(path, {.chunk_samples = 256});
    for (const auto& t : db.Trials(session))
      if (t.status != TrialStatus::kCompleted) RunAttempt(db, w, t.id);
  } catch (...) {
    _exit(3);
  }
  _exit(0);
}

TEST(Fault, SigkillWhileTrajectoriesAreWrittenNeverMixesAttempts) {
  test::TempDir dir;
  const std::string path = dir.File("kill.db");
  std::int64_t session = 0;
  {
    Database db(path);
    session = MakeSession(db);
    Plan(db, session, 30);
  }
  std::mt19937_64 rng(20261122);  // fixed seed: the kill moments are reproducible
  std::uniform_int_distribution<int> delay_ms(20, 150);
  int killed = 0, interrupted_rounds = 0, planned = 30;
  // At least 5 kills, and on until one interrupted an attempt that had committed chunks. A
  // child may finish every trial between two kills on a fast machine: then 30 more are
  // planned, so that later kills have trials to interrupt.
  for (int round = 0; round < 100 && (round < 5 || interrupted_rounds == 0); ++round) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) RunUntilKilled(path, session);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    killed += WIFSIGNALED(status);
    Database db(path);
    bool all_completed = true;
    for (const auto& t : db.Trials(session)) {
      interrupted_rounds +=
          t.status == TrialStatus::kRunning && !db.TrajectoryChunks(t.id, t.attempts).empty();
      all_completed = all_completed && t.status == TrialStatus::kCompleted;
    }
    if (all_completed && interrupted_rounds == 0) {
      Plan(db, session, 30, planned);
      planned += 30;
    }
  }
  EXPECT_GT(killed, 0) << "no child was killed mid-run: the test tests nothing";
  Resume(path, session);
  ExpectWhole(path, session, planned);
  // The kills left chunks of interrupted attempts behind; none of them is read with a trial.
  Database db(path);
  int interrupted = 0;
  for (const auto& t : db.Trials(session))
    for (int a = 1; a < t.completed_attempt; ++a)
      interrupted += !db.TrajectoryChunks(t.id, a).empty();
  EXPECT_GT(interrupted, 0) << "no interrupted attempt left chunks: the test tests nothing";
}

TEST(Fault, ReadOnlyOrTruncatedSharedMemoryFileIsRefusedNotSigbus) {
  test::TempDir dir;
  const std::string path = dir.File("shm.db");
  Database first(path);  // keeps -wal and -shm in place
  MakeSession(first);
  const std::string shm = path + "-shm";
  ASSERT_TRUE(std::filesystem::exists(shm));
  ASSERT_EQ(chmod(shm.c_str(), 0444), 0);
  try {
    Database second(path);
    ADD_FAILURE() << "a read-only -shm was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(shm), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("read-only"), std::string::npos) << e.what();
  }
  EXPECT_THROW(TrajectoryWriter w(path), InputError);
  ASSERT_EQ(chmod(shm.c_str(), 0644), 0);
  std::filesystem::resize_file(shm, 1000);
  EXPECT_THROW(Database second(path), InputError);
}

TEST(Fault, ReadOnlyWalIsRefusedAndNothingCommittedIsLost) {
  test::TempDir dir;
  const std::string path = dir.File("wal.db");
  std::int64_t session = 0;
  Database first(path);  // keeps -wal and -shm in place
  session = MakeSession(first);
  Plan(first, session, 2);
  {
    TrajectoryWriter w(path);
    ASSERT_TRUE(RunAttempt(first, w, first.Trials(session)[0].id));
  }
  const std::string wal = path + "-wal";
  ASSERT_TRUE(std::filesystem::exists(wal));
  ASSERT_EQ(chmod(wal.c_str(), 0444), 0);
  try {
    Database second(path);
    ADD_FAILURE() << "a read-only -wal was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(wal), std::string::npos) << e.what();
  }
  // Reading still works, and the completed trial is whole once the log is writable again.
  EXPECT_EQ(OpenForReading(path).Trials(session)[0].status, TrialStatus::kCompleted);
  ASSERT_EQ(chmod(wal.c_str(), 0644), 0);
  Resume(path, session);
  ExpectWhole(path, session, 2);
}

TEST(Fault, OneWriterPerDatabaseNamesTheHolder) {
  test::TempDir dir;
  const std::string path = dir.File("lease.db");
  int to_child[2], to_parent[2];
  ASSERT_EQ(pipe(to_child), 0);
  ASSERT_EQ(pipe(to_parent), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    char c = 1;
    {
      WriterLease lease(path);
      if (write(to_parent[1], &c, 1) != 1) _exit(3);
      if (read(to_child[0], &c, 1) != 1) _exit(4);
    }
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(to_parent[0], &c, 1), 1);
  try {
    WriterLease second(path);
    ADD_FAILURE() << "two writers held the lease";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("process " + std::to_string(pid)), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  ASSERT_EQ(write(to_child[1], &c, 1), 1);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_NO_THROW(WriterLease again(path));  // released when the holder ended
}

TEST(Fault, ConcurrentSchemaCreationWaitsInsteadOfFailing) {
  test::TempDir dir;
  const std::string path = dir.File("new.db");
  constexpr int kProcs = 4;
  int go[2];
  ASSERT_EQ(pipe(go), 0);
  std::vector<pid_t> pids;
  for (int i = 0; i < kProcs; ++i) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      close(go[1]);
      char c;
      (void)!read(go[0], &c, 1);  // all start together when the pipe closes
      try {
        Database db(path);
        _exit(db.SchemaVersion() == kSchemaVersion ? 0 : 5);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "child %d: %s\n", i, e.what());
        _exit(6);
      } catch (...) {
        _exit(7);
      }
    }
    pids.push_back(pid);
  }
  close(go[0]);
  close(go[1]);
  for (const pid_t pid : pids) {
    int status = 0;
    waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  }
  Database db(path);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
}

}  // namespace
}  // namespace hapticlab::db::fault_test
