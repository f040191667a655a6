#pragma once
/// @file Runs a study protocol for one participant and records everything: the session
/// state machine (consent -> training -> reference -> main, with breaks, abort and resume),
/// trial execution on a device back-end (today: the simulated lab), ratings committed one
/// transaction per trial, trajectories through the writer thread, events and provenance.
///
/// Guarantees: the plan is stored before the first trial; a trial's ratings and completion
/// marker commit together; `ResumeStudy` continues with exactly the trials not completed
/// (none twice, none skipped); a faulted trial is re-queued at the end of its phase in a
/// position that keeps the no-immediate-repeat constraint when any such position exists.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::runner {

/// What to record of each trial's interactions.
enum class RecordMode { kNone, kForce, kAll };

struct RunOptions {
  std::string db_path;
  std::string participant;       ///< pseudonymous code, e.g. "P07"
  int participant_index = -1;    ///< plan index; -1: the next free index in the study
  std::string device = "sim";    ///< device back-end (sim only in this build)
  RecordMode record = RecordMode::kAll;
  int stop_after_trials = -1;    ///< abort the session after this many trials (tests; -1: run all)
  double fault_rate = 0;         ///< sim: probability that a trial's device faults (tests)
  std::function<void(const std::string&)> log;  ///< progress lines (may be empty)
};

struct RunSummary {
  std::int64_t session_id = 0;
  std::string participant;
  std::string status;            ///< completed | aborted
  int planned = 0, completed = 0, executed = 0, faults = 0;
  double simulated_s = 0;        ///< stimulus time rendered (sim)
  double wall_s = 0;
};

/// Starts a new participant on `protocol` (creating the study in the database if needed).
/// @throws hapticlab::InputError on bad input (participant exists, protocol changed, ...)
RunSummary RunStudy(const protocols::Protocol& protocol, const RunOptions& options);

/// Continues the participant's session where it stopped (crash or abort).
RunSummary ResumeStudy(const RunOptions& options);

struct ParticipantStatus {
  std::string code;
  int planned = 0, completed = 0, faulted = 0;
  int duplicates = 0;  ///< planned trials completed more than once (must be 0)
  std::string session_status;
};
/// Progress of every participant (or one) in the database.
std::vector<ParticipantStatus> StudyStatus(const std::string& db_path, const std::string& participant = "");

}  // namespace hapticlab::runner
