#pragma once
// The session queue (private to runner): the planned trials of a session's phases in plan
// order, faulted ones re-queued at their phase's end, breaks, stops and aborts; then the
// adaptive phases.

#include <cstdint>

#include "hapticlab/db/database.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "lab.hpp"

namespace hapticlab::runner::internal {

// Executes the session's remaining trials and ends the session ("completed" or "aborted").
// Faulted trials go to the end of their phase.
RunSummary ExecuteSession(db::Database& database, const Lab& lab, std::int64_t session,
                          const db::Participant& part, const RunOptions& opt);

}  // namespace hapticlab::runner::internal
