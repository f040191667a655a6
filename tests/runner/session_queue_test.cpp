// The session queue (runner/src/session_queue.cpp): aborts end the session resumably,
// faulted trials are re-queued at their phase's end keeping the no-repeat constraint.

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/test_util.hpp"
#include "study_checks.hpp"

namespace hapticlab::runner::session_queue_test {
namespace {

using test_checks::ExpectCompleteAndWhole;
using test_checks::SmallProtocol;

TEST(SessionQueue, AbortThenResumeCompletesEveryTrialOnce) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  RunOptions o;
  o.db_path = dir.File("a.db");
  o.participant = "P02";
  o.record = RecordMode::kNone;
  o.stop_after_trials = 7;
  EXPECT_EQ(RunStudy(p, o).status, db::SessionStatus::kAborted);
  o.stop_after_trials = 5;
  EXPECT_EQ(ResumeStudy(o).status, db::SessionStatus::kAborted);
  o.stop_after_trials = -1;
  EXPECT_EQ(ResumeStudy(o).status, db::SessionStatus::kCompleted);
  ExpectCompleteAndWhole(o.db_path, 2);
  EXPECT_THROW(ResumeStudy(o), InputError);  // nothing left to resume
}

TEST(SessionQueue, FaultedTrialsAreRequeuedKeepingTheNoRepeatConstraint) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(SmallProtocol());
  RunOptions o;
  o.db_path = dir.File("f.db");
  o.participant = "P03";
  o.record = RecordMode::kNone;
  o.fault_rate = 0.25;
  const auto s = RunStudy(p, o);
  EXPECT_GT(s.faults, 0);
  EXPECT_EQ(s.completed, s.planned);
  ExpectCompleteAndWhole(o.db_path, 2);
  // Execution order (completion time) never puts one material twice in a row among rated
  // trials unless the runner logged that it had to.
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  int relaxed = 0, faults = 0, disconnects = 0;
  for (const auto& e : d.Events(se.id)) {
    relaxed += e.kind == db::EventKind::kConstraintRelaxed;
    // Each injected dropout: the watchdog's event, then the trial's re-queue.
    faults +=
        e.kind == db::EventKind::kDeviceFault && e.detail.find("re-queued") != std::string::npos;
    disconnects += e.kind == db::EventKind::kDeviceFault && e.detail.rfind("disconnect at", 0) == 0;
  }
  EXPECT_EQ(faults, s.faults);
  EXPECT_EQ(disconnects, s.faults) << "the link's dropouts, seen by the watchdog";
  std::map<std::int64_t, std::string> material;
  for (const auto& t : d.Trials(se.id)) material[t.id] = t.material;
  const auto order = d.RatedTrialsInCompletionOrder(se.id);
  ASSERT_EQ(order.size(), material.size() - 4);  // all but the 4 training trials
  int repeats = 0;
  for (std::size_t i = 1; i < order.size(); ++i)
    repeats += material[order[i]] == material[order[i - 1]];
  EXPECT_LE(repeats, relaxed);
}

}  // namespace
}  // namespace hapticlab::runner::session_queue_test
