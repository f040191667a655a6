#pragma once
// Checks shared by the study runner's tests (study_runner_test, session_queue_test).

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::test_checks {

inline std::string SmallProtocol() { return test::DataPath("protocols/small.toml"); }

// Every planned trial of every session exactly once, with all its ratings.
inline void ExpectCompleteAndWhole(const std::string& db_path, int criteria) {
  db::Database d(db_path);
  EXPECT_EQ(d.IntegrityCheck(), "ok");
  for (const auto& st : d.Studies())
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id)) {
        EXPECT_EQ(se.status, db::SessionStatus::kCompleted) << p.code;
        std::map<int, int> seen;
        for (const auto& t : d.Trials(se.id)) {
          ++seen[t.plan_index];
          EXPECT_EQ(t.status, db::TrialStatus::kCompleted) << p.code << " trial " << t.plan_index;
          const auto r = d.Ratings(t.id);
          EXPECT_EQ(r.size(),
                    t.phase == PhaseKind::kTraining ? 0u : static_cast<std::size_t>(criteria))
              << t.plan_index;
        }
        for (const auto& [i, n] : seen) EXPECT_EQ(n, 1) << "plan index " << i;
      }
}

}  // namespace hapticlab::runner::test_checks
