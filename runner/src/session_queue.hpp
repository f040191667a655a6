#pragma once
// The session queue (private to runner): the planned trials of a session's phases in plan
// order, faulted ones re-queued at their phase's end, breaks, stops and aborts; then the
// adaptive phases.

#include <cstdint>

#include "hapticlab/db/database.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "lab.hpp"

namespace hapticlab::runner::internal {

// Executes the session's remaining trials on `rig` and ends the session ("completed" or
// "aborted"). A rig the caller passed in RunOptions::rig is logged as the session's 'device'.
// Faulted trials go to the end of their phase. An error (exception) marks the session
// "failed" with a 'stopped' event naming it, then propagates.
RunSummary ExecuteSession(db::Database& database, const Lab& lab, std::int64_t session,
                          const db::Participant& part, const RunOptions& opt, Rig& rig);

}  // namespace hapticlab::runner::internal
