#pragma once
/// @file `hapticlab analyze`: the analyses a study's protocol declares, run on its SQLite
/// record, written as a report (Markdown, CSV tables, SVG and PNG figures) that mirrors the
/// dissertation's tables and figures (Tables 4.1, 4.2, 5.2-5.5; Figs. 4.5, 4.8, 5.7, 5.8).

#include <string>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct ReportOptions {
  std::string out_dir;
  bool figures = true;
};

struct ReportResult {
  std::string markdown;              ///< path of report.md
  std::vector<std::string> files;    ///< every file written
  std::vector<std::string> studies;  ///< studies analysed
};

/// Ratings of every study in the database as a long table with keys study, participant,
/// phase, material, comparison, method, repetition, criterion (response: score).
LongTable RatingsFromDatabase(const std::string& db_path);

/// Runs the analyses of every study in the database. @throws InputError when the database
/// holds no ratings.
ReportResult Analyze(const std::string& db_path, const ReportOptions& options);

}  // namespace hapticlab::stats
