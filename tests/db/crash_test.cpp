// A trial's ratings are all present or all absent after the process is killed mid-commit.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <thread>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::crash_test {
namespace {

constexpr int kCriteria = 8;  // ratings per trial

// Child: completes trials forever (until killed), each with kCriteria ratings.
[[noreturn]] void CompleteTrialsForever(const std::string& path, std::int64_t session) {
  try {
    Database db(path);
    for (int i = 0;; ++i) {
      const auto id = db.AddTrial({.session_id = session,
                                   .plan_index = i,
                                   .phase = PhaseKind::kMain,
                                   .material = "m" + std::to_string(i % 10)});
      db.StartTrial(id);
      std::vector<Rating> r;
      for (int c = 0; c < kCriteria; ++c) r.push_back({"c" + std::to_string(c), 50.0 + c, 1.0});
      db.CompleteTrial(id, r);
    }
  } catch (...) {
    _exit(3);
  }
}

TEST(Crash, SigkillMidCommitLeavesEachTrialWholeOrEmpty) {
  test::TempDir dir;
  const std::string path = dir.File("crash.db");
  std::int64_t session = 0;
  {
    Database db(path);
    session = test::AddStudySession(db, {.name = "crash", .protocol_toml = "x", .seed = 1}).session;
  }
  std::mt19937_64 rng(20261121);  // fixed seed: the kill moments are reproducible
  std::uniform_int_distribution<int> delay_ms(30, 400);
  for (int round = 0; round < 6; ++round) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) CompleteTrialsForever(path, session);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ASSERT_EQ(kill(pid, SIGKILL), 0);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "child exited before the kill (status " << status << ")";
  }
  Database db(path);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
  const auto trials = db.Trials(session);
  ASSERT_GT(trials.size(), 6u);
  int completed = 0;
  for (const auto& t : trials) {
    const auto n = db.Ratings(t.id).size();
    if (t.status == TrialStatus::kCompleted) {
      EXPECT_EQ(n, static_cast<std::size_t>(kCriteria)) << "trial " << t.id;
      ++completed;
    } else {
      EXPECT_EQ(n, 0u) << "trial " << t.id << " has ratings but no completion marker";
    }
  }
  EXPECT_GT(completed, 0);
}

}  // namespace
}  // namespace hapticlab::db::crash_test
