#pragma once
/// @file Real-time timing of each trial side (schema v6 table `side_timing`): per loop
/// (force, vibration) the rate asked and achieved, wake-up lateness and tick duration
/// percentiles, the lateness histogram (sparse, 0.5 us bins: hapticlab/core/latency_histogram.hpp),
/// deadline misses, recording overflows, audio underruns, and what the loop thread got
/// (scheduling, memory locking, timer slack). One row per trial, attempt, side and loop.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"

namespace hapticlab::db {

struct SideTiming {
  std::int64_t trial_id = 0;
  int attempt = 0;
  std::string side;            ///< the side's stream prefix: "left", "right", "i1", ...
  std::string loop;            ///< "force" | "vibration"
  std::string clock = "real";  ///< "real" | "virtual" (virtual: lateness 0, durations not measured)
  double rate_hz = 0, achieved_rate_hz = 0;
  std::int64_t ticks = 0, deadline_misses = 0;
  double late_p50_us = 0, late_p99_us = 0, late_p999_us = 0, late_max_us = 0;
  double tick_p50_us = 0, tick_p99_us = 0, tick_p999_us = 0, tick_max_us = 0;
  std::string late_histogram;  ///< LatencySummary::Sparse()
  std::int64_t recording_overflows = 0, audio_underruns = 0;
  std::string priority;  ///< e.g. "SCHED_FIFO 80", "not requested (normal scheduling)"
  bool memory_locked = false;
  std::int64_t timer_slack_ns = -1;
};

/// Stores (or replaces) one row.
void SaveSideTiming(Database& d, const SideTiming& t);
/// Rows of every trial of a study (by study id), in trial and insertion order.
std::vector<SideTiming> StudySideTimings(const Database& d, std::int64_t study_id);

}  // namespace hapticlab::db
