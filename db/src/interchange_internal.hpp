#pragma once
// What the BIDS and XDF exports share (private to the db module): a session's completed
// trials with their ratings and recordings, read through the Database API, the session
// clock, and the meaning of the channel names.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"

namespace hapticlab::db::internal {

/// Unit (SI symbol) and meaning of a recorded channel, from its name ("fx_N", "acc_mps2").
struct ChannelMeaning {
  std::string unit;         ///< e.g. "N", "m/s^2"; "n/a" for a dimensionless flag
  std::string description;  ///< one sentence
};
ChannelMeaning DescribeChannel(const std::string& name);

/// Letters and digits of `s` only (BIDS labels).
std::string Alnum(const std::string& s);

/// Microseconds since 1970 of an ISO-8601 UTC stamp as the database writes them
/// ("2026-11-22T17:42:55.123Z"); nullopt when empty or not of that form. Integers, so that
/// differences of stamps are exact (seconds since 1970 as a double lose 0.2 us).
std::optional<std::int64_t> ParseUtcMicros(const std::string& iso);

/// One trajectory stream of one trial: its chunks in time order.
struct StreamRecording {
  std::string stream;
  double rate_hz = 0;
  std::vector<std::string> channels;
  std::vector<TrajectoryChunk> chunks;
  /// Time just after the last sample, relative to the stream's own zero [s].
  double end_s() const;
  std::size_t sample_count() const;
};

/// A completed trial, placed on the session clock.
struct TrialRecord {
  Trial trial;
  std::vector<Rating> ratings;
  std::vector<StreamRecording> streams;  ///< sorted by stream name
  double wall_start_s =
      0;                  ///< when the (completing attempt of the) trial started, session-relative
  double origin_s = 0;    ///< where its first stimulus begins on the session clock
  double stimulus_s = 0;  ///< both stimuli, back to back (left then right)
  std::map<std::string, double> offset_s;  ///< per stream: its zero relative to origin_s
};

/// One session with everything the exports write.
struct SessionRecord {
  Study study;
  Participant participant;
  Session session;
  int number = 1;                   ///< 1-based among the participant's sessions
  std::vector<TrialRecord> trials;  ///< completed trials, in the order they ran
  std::vector<Event> events;
  std::vector<double> event_time_s;  ///< each event on the session clock
};

/// Every session (of `participant` when not empty), in study, participant, session order.
/// The session clock: 0 = the session's start stamp. A trial begins at its start stamp, or
/// where the previous trial's stimuli and ratings end when that is later (a simulated
/// session runs faster than real time, so its stamps alone would overlap the recordings);
/// the right stimulus follows the left one. Events keep their offset from the latest trial
/// start before them.
std::vector<SessionRecord> LoadSessions(const Database& db, const std::string& participant);

}  // namespace hapticlab::db::internal
