#pragma once
// A session on the small test protocol (tests/data/protocols/small.toml: criteria roughness
// and overall, stimulus 0.5 s, methods FF without vibration and Hybrid with it) on the
// generic simulated rig, with a database holding one study, participant and session, for
// the tests of one trial side (stimulus_side_test.cpp) and one trial (trial_test.cpp).

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "../../runner/src/lab.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::test_trial {

struct Session {
  test::TempDir dir;
  protocols::Protocol protocol = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  internal::Lab lab = internal::LoadLab(protocol, "sim");
  std::unique_ptr<Rig> rig = OpenRig({.device = "sim"});
  std::string db_path = dir.File("s.db");
  db::Database database{db_path};
  std::int64_t session = 0;

  Session() {
    lab.protocol = &protocol;
    session =
        test::AddStudySession(database, {.name = protocol.name, .protocol_toml = "# p"}).session;
  }
  // A started trial of this session.
  db::Trial Trial(PhaseKind phase, const std::string& left, const std::string& right,
                  const std::string& method, int plan_index = 0) {
    db::Trial t{.session_id = session,
                .plan_index = plan_index,
                .phase = phase,
                .material = internal::ParseStimulus(left).id,
                .comparison = "virtual",
                .method = method,
                .left = left,
                .right = right};
    t.id = database.AddTrial(t);
    t.attempts = database.StartTrial(t.id);
    return t;
  }
};

}  // namespace hapticlab::runner::test_trial
