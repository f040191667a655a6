#pragma once
/// @file The export formats, by name (`hapticlab export --format NAME`). Adding one is one
/// file and one line: write `ExportFormat MyFormat()` in db/src/export_<name>.cpp and add it
/// to the list in db/src/export_formats.cpp (docs/architecture.md, "Adding an export"). The
/// CLI's --format choices, its help and its checks of --participant, --trajectories and a
/// file name in --out come from these entries.

#include <functional>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"

namespace hapticlab::db {

/// What an export is asked for (the CLI's options).
struct ExportRequest {
  std::string out;            ///< a directory, or a file for formats with file_extension
  std::string participant;    ///< only this participant ("": all; selects_participants)
  bool trajectories = false;  ///< write trajectories (chooses_trajectories formats)
  ExportProgress progress;    ///< one line per participant (and notes); may be empty
};

struct ExportFormat {
  std::string name;  ///< --format NAME
  /// The CLI's help lines for the format, after its name ("tidy long-format CSV ...").
  std::string help;
  bool selects_participants = false;  ///< honours ExportRequest::participant
  bool chooses_trajectories = false;  ///< honours ExportRequest::trajectories (else always)
  bool counts_streams = false;        ///< its files report streams and samples, not rows
  std::string file_extension;         ///< ".xdf": an --out ending in it names one file
  /// Writes the export; the files written.
  std::function<std::vector<ExportedFile>(const Database&, const ExportRequest&)> write;
  /// What the files hold, for the summary line ("3 tables, 120 rows").
  std::function<std::string(const std::vector<ExportedFile>&)> describe;
};

/// Every format: the built-in ones (csv, bids, xdf) in that order, then those registered.
const std::vector<ExportFormat>& ExportFormats();
/// The format named `name`, or nullptr.
const ExportFormat* FindExportFormat(const std::string& name);
/// Adds a format at run time (a plug-in, a test); its name must be new.
/// @throws std::logic_error for a name already taken
void RegisterExportFormat(ExportFormat format);

// The built-in formats (one file each).
ExportFormat CsvExportFormat();   ///< export.cpp
ExportFormat BidsExportFormat();  ///< export_bids.cpp
ExportFormat XdfExportFormat();   ///< export_xdf.cpp

}  // namespace hapticlab::db
