#pragma once
/// @file Exports of a study record in the formats other lab tools read: BIDS (the Brain
/// Imaging Data Structure, checked by the official bids-validator) and XDF (the Lab
/// Streaming Layer's file format, read by libxdf, pyxdf, MNE, EEGLAB and FieldTrip).
/// docs/analysis.md shows how to load both in R, pandas and MNE.

#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"

namespace hapticlab::db {

/// Writes a BIDS dataset into `out_dir` (created when missing; files already there with
/// the same names are replaced):
/// - `dataset_description.json`, `README`, `participants.tsv` + `.json` (pseudonymous codes
///   only: `sub-<code without '-' and '_'>` and the code itself);
/// - per participant and session `sub-X/ses-N/beh/sub-X_ses-N_task-T_beh.tsv` + `.json`:
///   one row per rating with the trial's conditions;
/// - per completed trial and recorded stream `..._run-<plan index +
/// 1>_recording-<stream>_physio.tsv.gz`
///   + `.json` (SamplingFrequency, StartTime, Columns, each column's Units and Description);
///   samples missing inside a recording (a gap between two chunks) are written as `n/a`;
/// - `code/`: each study's protocol and the material models as stored, with `hashes.tsv`
///   (SHA-256 as recorded in the database).
/// Only completed trials are exported (a faulted or aborted attempt's samples are not).
/// Throws InputError (CLI exit 2) when two participants map to one BIDS label, and
/// std::runtime_error naming the file on I/O failure.
/// `progress`: one line per participant written.
std::vector<ExportedFile> ExportBids(const Database& db, const std::string& out_dir,
                                     const ExportProgress& progress = {});

/// Writes XDF files, one per session. `out` ending in ".xdf" names the file and then the
/// selection must hold exactly one session; otherwise `out` is a directory (created when
/// missing) that receives `sub-<code>_ses-<n>.xdf` per session.
/// Streams per session: one per recorded trajectory stream (float32, its nominal rate, one
/// timestamp per stored chunk, channel labels and units in the header), `events` (string
/// markers: trial starts with their conditions, and the session's logged events) and
/// `ratings` (string markers at stimulus end + response time). Every timestamp is on one
/// clock: seconds since the session started (docs/analysis.md, "XDF clock").
/// @param participant only this participant's sessions (empty: all)
/// @param progress one line per participant written
/// Throws InputError (exit 2) for an unknown participant or a file name with several
/// sessions; std::runtime_error naming the file on I/O failure.
std::vector<ExportedFile> ExportXdf(const Database& db, const std::string& out,
                                    const std::string& participant = "",
                                    const ExportProgress& progress = {});

}  // namespace hapticlab::db
