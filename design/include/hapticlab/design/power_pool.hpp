#pragma once
/// @file Simulated studies for `hapticlab study power` and the observer calibration.
///
/// Two stages. (1) Physics, through the runner: `RecordFeltPool` runs the protocol's
/// simulated sessions for a pool of participants (plan indices 0..K-1, each through
/// runner::RunStudy on the simulated rig: every trial side in RtEngine on a virtual clock) and
/// keeps, per rated trial, the observer's feature distance per criterion
/// (runner::RunOptions::on_felt). (2) Ratings: `SimulateRatings` builds a study of any size by
/// drawing each simulated participant's interactions from the pool (with replacement) and rating
/// them with a fresh sim::Observer (new offsets, scale range, participant x material and x method
/// effects, trial noise and lapses) through Observer::RateDistance — the code the runner's observer
/// uses. The physics is the expensive part (seconds per participant); re-rating costs
/// microseconds, which is what makes hundreds of simulated studies per second possible.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::design {

struct FeltPool {
  std::string protocol;  ///< study name
  std::vector<std::string> criteria;
  double scale_min = 0, scale_max = 100;
  sim::ObserverParams observer;  ///< the protocol's observer (its file or the profiles')
  std::vector<std::vector<runner::FeltTrial>>
      participants;  ///< rated trials of each pool participant, plan order
};

/// Runs `pool_size` simulated participants (plan indices first_index..first_index+pool_size-1)
/// through the runner, each in its own temporary database (removed afterwards), `threads` at a
/// time.
/// @throws InputError as runner::RunStudy does
FeltPool RecordFeltPool(const protocols::Protocol& protocol, int pool_size, int threads = 2,
                        const std::function<void(const std::string&)>& log = {},
                        int first_index = 0);

/// The observer of a protocol as the runner would load it (observer file, else profiles).
sim::ObserverParams ProtocolObserver(const protocols::Protocol& protocol);

/// The simulated observer model that rates simulated studies (power depends on it), and how
/// to name it.
struct ObserverModel {
  sim::ObserverParams params;
  std::string file;    ///< the observer file (as given, or the protocol's folder joined with
                       ///< its `[study] observer`); "" for the built-in defaults
  std::string sha256;  ///< hex SHA-256 of the file's bytes; "" for the built-in defaults
  /// "FILE (sha256 HEX)" or "built-in uncalibrated".
  std::string Describe() const;
};

/// `choice` "": the protocol's `[study] observer` file; "builtin": sim::ObserverParams'
/// uncalibrated defaults; anything else: an observer file (sim::LoadObserver).
/// @throws InputError naming the protocol and `option` when `choice` is "" and the protocol
///         names no observer file, or as sim::LoadObserver
ObserverModel ChooseObserver(const protocols::Protocol& protocol, const std::string& choice,
                             const std::string& option = "--observer");

/// A simulated study of `participants` participants rated by `observer`: long table with keys
/// participant, criterion, phase, material, comparison, method (response score); with
/// `main_only` just the main phase's rows and the keys participant, criterion, method,
/// material (what stats::AnalyseOnce analyses, as the report does).
stats::LongTable SimulateRatings(const FeltPool& pool, const sim::ObserverParams& observer,
                                 int participants, Rng& rng, bool main_only);

}  // namespace hapticlab::design
