#pragma once
/// @file Monte-Carlo power of a within-subjects design (`hapticlab study power`): many
/// simulated data sets per participant count, each analysed with the repeated-measures ANOVA
/// the report runs (stats/report.hpp: per criterion, within factors method and material),
/// tallied into the probability that each effect reaches p < alpha, with a Wilson score
/// interval for that probability (Wilson 1927; Brown, Cai & DasGupta 2001 recommend it over
/// the Wald interval for Monte-Carlo proportions), and the mean partial eta^2.
///
/// Reproducibility: simulation s at participant count n draws from
/// Rng(DeriveSeed(DeriveSeed(seed, n), s)); results are reduced in simulation order, so the
/// outcome does not depend on the number of threads nor on how the simulations are split
/// into shards (`--shard i/N` runs simulations s with s mod N == i; merging sums the tallies).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

/// One effect's tally at one participant count.
struct PowerTally {
  std::string criterion, effect;
  long hits = 0;       ///< simulations with p < alpha
  long runs = 0;       ///< simulations analysed
  double sum_pes = 0;  ///< sum of partial eta^2 over the runs
  double power() const { return runs ? static_cast<double>(hits) / static_cast<double>(runs) : 0; }
  double mean_pes() const { return runs ? sum_pes / static_cast<double>(runs) : 0; }
};

struct PowerRow {
  int participants = 0;
  std::vector<PowerTally> effects;
};

struct PowerResult {
  std::string protocol;
  /// The protocol's title ([study] title), for the plot's title; empty: the protocol's name.
  std::string title;
  /// The simulated observer model that rated the studies (power depends on it): its file and
  /// the SHA-256 of the file's bytes, both empty for the built-in uncalibrated defaults.
  std::string observer_file, observer_sha256;
  /// "FILE (sha256 HEX)" or "built-in uncalibrated".
  std::string ObserverDescription() const;
  long simulations = 0;  ///< simulations per participant count (of the whole run, all shards)
  std::uint64_t seed = 0;
  int shard = 0, shards = 1;  ///< which part of the simulations this result holds (merged: 0 of 1)
  std::vector<PowerRow> rows;
};

struct PowerOptions {
  std::vector<int> participants;  ///< e.g. 8, 12, 16, 20, 30
  long simulations = 200;
  std::uint64_t seed = 1;
  int shard = 0, shards = 1;
  int threads = 2;
  double alpha = 0.05;
  /// Effects to report ("method", "material", "method:material"); empty: all.
  std::vector<std::string> effects;
  /// Called after each finished simulation with (done, total); from the calling thread.
  std::function<void(long, long)> progress;
};

/// A simulated data set for `participants` participants: long table with key columns
/// participant, criterion and the within factors, response score. Called concurrently
/// from several threads: it must only use `rng` and its own locals.
using StudyGenerator = std::function<LongTable(int participants, Rng& rng)>;

/// The analysis each simulated data set gets: per criterion (rows of the `criterion` key,
/// in order of first appearance), RmAnova(participant; within factors) — the factors are
/// the key columns other than participant and criterion with at least two levels.
/// @throws InputError as RmAnova does
std::vector<PowerTally> AnalyseOnce(const LongTable& data, double alpha);

PowerResult SimulatePower(const std::string& protocol, const StudyGenerator& generate,
                          const PowerOptions& options);

/// Wilson score interval (95 %) for `hits` successes in `n` trials.
void WilsonInterval(long hits, long n, double* low, double* high);

/// JSON as documented in docs/studies.md (`observer`, `power`, `ci_low`, `ci_high`,
/// `mean_pes`), plus
/// `shard`, `shards` and the raw tallies (`hits`, `runs`, `sum_pes`) that --merge reads.
std::string PowerToJson(const PowerResult& r);
/// @throws InputError naming the file and what is wrong
PowerResult PowerFromJson(const std::string& text, const std::string& file);
/// Sums shards of one run (same protocol, observer, seed, simulations, participant counts;
/// each shard once). @throws InputError when they do not fit together
PowerResult MergePower(const std::vector<PowerResult>& parts,
                       const std::vector<std::string>& files);

/// Text table: the observer, then one line per participant count and effect.
std::string PowerTable(const PowerResult& r);
/// Power curves (one per criterion x effect, with markers) as <base>.svg/.png, the observer
/// named under the title (and in the SVG's <desc>), with the 0.8 line and the chosen sample
/// size marked: the smallest participant count from which every curve that reaches 0.8 stays
/// there. Returns the files.
std::vector<std::string> DrawPowerCurves(const PowerResult& r, const std::string& base);

/// Smallest participant count whose power for (criterion, effect) is >= target; 0: none.
int ParticipantsFor(const PowerResult& r, const std::string& criterion, const std::string& effect,
                    double target);

}  // namespace hapticlab::stats
