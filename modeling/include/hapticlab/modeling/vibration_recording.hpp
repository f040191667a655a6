#pragma once
/// @file Contact-acceleration recordings for vibration modeling (dissertation ch. III.3):
/// one scan condition (steady speed and normal force) per recording, read from measurement
/// CSV v1 files (core/measurement.hpp), whole or cut into their steady parts.
/// Units: speed [m/s] (tangential, in the sample plane), force [N] (normal), rate [Hz],
/// acceleration [m/s^2] (normal to the sample).

#include <string>
#include <vector>

namespace hapticlab::modeling {

/// One scan condition: acceleration at a steady speed and normal force.
struct Recording {
  std::string file;
  double speed_mps = 0, force_N = 0;  ///< scan condition
  double rate_hz = 0;                 ///< sample rate of `acc`
  std::vector<double> acc;            ///< normal acceleration [m/s^2]
};

/// Reads one measurement CSV v1 with an `acc_mps2` column. Speed and force come from the
/// `# speed_mps:` / `# force_N:` metadata or, when absent, from the rows (mean tangential
/// speed and mean normal force, which must be steady: coefficient of variation < 25 %). The
/// rate comes from `# rate_hz:` or the time stamps, which must be uniform (a gap of more than
/// 1.5 sample periods is an error naming its line). Clipping (20 or more samples at the
/// extreme value) is an error. @throws InputError naming file, line and field.
Recording LoadRecording(const std::string& path);
/// A recording without condition metadata, cut into its steady parts: 0.25 s blocks are
/// grouped while their mean speed and force stay within 15 % of the group's first block;
/// every group of at least `min_s` seconds becomes one condition. With metadata, the whole
/// file is one condition (as LoadRecording).
std::vector<Recording> LoadRecordingSegments(const std::string& path, double min_s = 1.0);
/// Every `*.csv` in a folder, sorted by name (files without metadata are segmented).
/// @throws InputError when there is none, listing every bad file.
std::vector<Recording> LoadRecordings(const std::string& dir);

}  // namespace hapticlab::modeling
