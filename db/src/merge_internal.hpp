#pragma once
// db merge internals (merge_copy.cpp): copying one input into the merge's build file.

#include <sqlite3.h>

#include <string>

#include "hapticlab/db/merge.hpp"

namespace hapticlab::db::internal {

// Copies every participant with a session (site-qualified code), its sessions, trials,
// ratings, events, trajectories and timing, and the input's studies, models and measurements
// not yet in `build`, with new ids that follow the site-qualified codes. The first input's
// schema_version rows are kept (the inputs' migration times, none of the merge's).
void CopyInput(sqlite3* build, const std::string& input_path, bool first);
// Sites, participants, sessions and ratings of a merged file.
MergeSummary Summarize(sqlite3* merged);

}  // namespace hapticlab::db::internal
