#pragma once
/// @file Contact-acceleration recordings for vibration modeling (dissertation ch. III.3):
/// one scan condition (steady speed and normal force) per recording, read from measurement
/// CSV v1 files (core/measurement.hpp), whole or cut into their steady parts.
/// Units: speed [m/s] (tangential, in the sample plane), force [N] (normal), rate [Hz],
/// acceleration [m/s^2] (normal to the sample).

#include <optional>
#include <string>
#include <vector>

namespace hapticlab::modeling {

/// What a sound file cannot say about itself, from its sidecar (sound_recording.hpp) or the
/// command line. Unset fields leave the defaults: condition unlabelled, uncalibrated, one
/// channel as is or three as x, y, z.
struct SoundLabels {
  std::optional<double> speed_mps, force_N;  ///< the scan condition
  bool unlabelled = false;                   ///< condition = "unlabelled": known to be unknown
  std::optional<double> scale_mps2;          ///< m/s^2 per unit sample (integer full scale = 1)
  bool uncalibrated = false;                 ///< calibration = "uncalibrated"
  std::vector<int> axes;                     ///< 1-based channels of the axes (1 to 3 of them)
  std::string material;
};

/// One scan condition: acceleration at a steady speed and normal force.
struct Recording {
  std::string file;
  double speed_mps = 0, force_N = 0;  ///< scan condition
  double rate_hz = 0;                 ///< sample rate of `acc`
  std::vector<double> acc;            ///< normal acceleration [m/s^2] (file units if uncalibrated)
  bool labelled = true;               ///< false: the condition is unknown (speed and force are 0)
  bool calibrated = true;             ///< false: `acc` is in the file's own units, not m/s^2
  int channels = 1;                   ///< axes reduced into `acc` (by DFT321 when more than one)
};

/// Reads one measurement CSV v1 with an `acc_mps2` column. Speed and force come from the
/// `# speed_mps:` / `# force_N:` metadata or, when absent, from the rows (mean tangential
/// speed and mean normal force, which must be steady: coefficient of variation < 25 %). The
/// rate comes from `# rate_hz:` or the time stamps, which must be uniform (a gap of more than
/// 1.5 sample periods is an error naming its line). Clipping (20 or more samples at the
/// extreme value) is an error. @throws InputError naming file, line and field.
/// A .wav or .flac file is read by ReadSoundRecording (sound_recording.hpp) with `labels` as
/// the defaults its sidecar overrides. A vibration-only CSV (t_s and acc_mps2, no x_m) takes
/// its condition from the metadata or is unlabelled. `# calibration: uncalibrated` marks
/// acc_mps2 as being in the sensor's own units.
Recording LoadRecording(const std::string& path, const SoundLabels& labels = {});
/// A recording without condition metadata, cut into its steady parts: 0.25 s blocks are
/// grouped while their mean speed and force stay within 15 % of the group's first block;
/// every group of at least `min_s` seconds becomes one condition. With metadata, the whole
/// file is one condition (as LoadRecording).
/// Sound files and vibration-only CSVs are one recording each.
std::vector<Recording> LoadRecordingSegments(const std::string& path, double min_s = 1.0,
                                             const SoundLabels& labels = {});
/// Every `*.csv`, `*.wav` and `*.flac` in a folder, sorted by name (CSV files with
/// kinematics but without metadata are segmented); `labels` as for LoadRecording.
/// @throws InputError when there is none, listing every bad file.
std::vector<Recording> LoadRecordings(const std::string& dir, const SoundLabels& labels = {});

/// @throws InputError listing every unlabelled recording (`command` names what needs it).
void RequireConditions(const std::vector<Recording>& recordings, const std::string& command);
/// Recordings of one (speed, force) condition joined into one (their samples concatenated,
/// files named "a + b"), for fitters that take one recording per condition; unlabelled
/// recordings are kept apart. @throws InputError when pooled recordings differ in rate.
std::vector<Recording> PoolByCondition(const std::vector<Recording>& recordings);
/// True when every recording is in m/s^2.
bool AllCalibrated(const std::vector<Recording>& recordings);

}  // namespace hapticlab::modeling
