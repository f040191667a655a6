#pragma once
/// @file Tidy long-format CSV export of a study record, for R and pandas.

#include <functional>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"

namespace hapticlab::db {

/// One file written by an export.
struct ExportedFile {
  std::string path;
  std::size_t rows = 0;     ///< table rows (CSV, TSV; a physio TSV: samples); 0 for others
  std::size_t streams = 0;  ///< XDF: streams in the file (else 0)
  std::size_t samples = 0;  ///< XDF: samples of all its streams, one per marker (else 0)
};

/// Receives one line per participant as an export finishes it ("sub-P01: ..."); may be empty.
using ExportProgress = std::function<void(const std::string&)>;

/// What the CSV export would write as trajectories: completed trials' completing attempts.
struct TrajectorySize {
  std::size_t streams = 0;  ///< distinct stream names
  std::size_t samples = 0;  ///< rows the trajectory CSVs would hold
  std::size_t values = 0;   ///< samples x channels
  /// About the bytes of the CSVs (measured ~10.5 bytes per value plus the row's keys).
  std::size_t estimated_bytes = 0;
};
/// Counts what the trajectory CSVs would hold, from the chunks' stored counts (no blob read).
TrajectorySize CountTrajectories(const Database& db);

/// Every file names a trial by `trial`, its 1-based number in the participant's plan (as
/// `study plan`, the run's log and the console number it); database ids of trials never
/// appear. Writes into `out_dir` (created when missing):
/// - `ratings.csv`: one row per rating, with its study, participant, trial and design cells
///   and its source ("simulated" or the participant's input device; docs/formats.md);
/// - `trials.csv`: one row per trial with status and attempts;
/// - `events.csv`: one row per event;
/// - `trajectory_<stream>.csv`: one row per sample (study, participant, trial, t_s, then
///   the stream's channels) of each completed trial's completing attempt only. Floats are
///   printed with 9 significant digits, so float32 samples round-trip exactly.
/// Throws std::runtime_error naming the file on I/O failure, and InputError (naming the
/// database) when a trial's chunks no longer match the sample counts stored at its
/// completion (Database::VerifyTrajectories) or a chunk's blob does not match its counts.
/// @param trajectories false: ratings, trials and events only (trajectories stay in the db)
/// @param progress with trajectories, one line per participant
std::vector<ExportedFile> ExportCsv(const Database& db, const std::string& out_dir,
                                    bool trajectories = true, const ExportProgress& progress = {});

}  // namespace hapticlab::db
