#pragma once
/// @file `hapticlab analyze`: the analyses a study's protocol declares, run on its SQLite
/// record, written as a report (Markdown, CSV tables, SVG and PNG figures) that mirrors the
/// dissertation's tables and figures (Tables 4.1, 4.2, 5.2-5.5; Figs. 4.5, 4.8, 5.7, 5.8).

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::db {
class Database;
struct Study;
}  // namespace hapticlab::db

namespace hapticlab::stats {

struct ReportOptions {
  std::string out_dir;
  bool figures = true;
  /// Keep the simulated observer's ratings in a study that also holds a person's ratings
  /// (by default they are excluded there, and the report says how many).
  bool include_simulated = false;
  /// The sphericity correction of within effects ("GG", "HF", "none"; afex's names),
  /// overriding each protocol's `[analysis] correction`; empty: the protocol's.
  std::string correction;
  /// A section written after each study's opening lines (`analyze --plan`: preregistration
  /// and deviations from the plan, replication/deviations.hpp); empty: none.
  std::function<std::string(const db::Database&, const db::Study&)> study_section;
};

struct ReportResult {
  std::string markdown;              ///< path of report.md
  std::vector<std::string> files;    ///< every file written
  std::vector<std::string> studies;  ///< studies analysed
};

/// Which ratings RatingsFromDatabase kept and left out, per study.
struct RatingSources {
  std::map<std::string, std::size_t> human;               ///< a person's ratings kept, by study
  std::map<std::string, std::size_t> simulated_kept;      ///< the simulated observer's, kept
  std::map<std::string, std::size_t> simulated_excluded;  ///< the simulated observer's, left out
};

/// Ratings of every study in the database as a long table with keys study, participant,
/// phase, material, comparison, method, repetition, criterion (response: score).
/// A study holding any rating from a person (source other than "simulated") is a human
/// study: its simulated ratings are left out unless `include_simulated`. A study rated only
/// by the simulated observer keeps them all.
LongTable RatingsFromDatabase(const std::string& db_path, bool include_simulated = false,
                              RatingSources* sources = nullptr);

/// Runs the analyses of every study in the database. @throws InputError when the database
/// holds no ratings.
ReportResult Analyze(const std::string& db_path, const ReportOptions& options);

/// The methods-section sentence on real-time timing of a study (its `side_timing` rows):
/// per loop the requested and achieved rates and the wake-up lateness percentiles (p50, p99,
/// p99.9, max) of all real-clock ticks (the trial sides' histograms merged), deadline misses,
/// tick duration, recording overflows and audio underruns, and what the loop threads got.
/// A study run only on a virtual clock says so.
std::string TimingMethodsSentence(const db::Database& d, std::int64_t study_id);

}  // namespace hapticlab::stats
