#pragma once
/// @file Vibration recordings as labs keep them: WAV and FLAC files (any rate, 16/24/32-bit
/// integer or float, one or more channels), read with libsndfile in blocks so a long file
/// never exists in memory as text. What a sound file cannot say - the scan condition, the
/// scale to m/s^2, which channels are the x/y/z axes - comes from a sidecar `NAME.toml`
/// beside `NAME.wav` (docs/formats.md) or from command-line defaults. Several axes are
/// reduced to one by DFT321 (dft321.hpp), as the Penn Haptic Texture Toolkit does.

#include <string>
#include <vector>

#include "hapticlab/modeling/vibration_recording.hpp"

namespace hapticlab::modeling {

/// True for a .wav or .flac name (any case).
bool IsSoundFile(const std::string& path);
/// NAME.toml beside NAME.wav.
std::string SidecarPath(const std::string& sound_path);
/// Reads a sidecar's [recording] table: speed_mps, force_N, condition ("labelled" or
/// "unlabelled"), scale_mps2, calibration ("calibrated" or "uncalibrated"), axes, material.
/// @throws InputError naming the sidecar, the line and the key (unknown keys, wrong types,
/// non-positive numbers, contradictions such as a scale on an uncalibrated recording).
SoundLabels ReadSoundSidecar(const std::string& sidecar_path);
/// `defaults` (the command line) with every field the sidecar sets replaced by the sidecar's.
SoundLabels MergeLabels(const SoundLabels& defaults, const SoundLabels& sidecar);
/// Checks labels given on the command line (`field` prefix for messages is the flag names).
void CheckLabels(const SoundLabels& l, const std::string& file);

/// A sound file's header: channels, rate, frames and the sample format in words.
struct SoundInfo {
  int channels = 0;
  double rate_hz = 0;
  long long frames = 0;
  std::string format;  ///< e.g. "WAV, 24-bit PCM"
};
/// @throws InputError when the file is not a readable WAV or FLAC file.
SoundInfo ProbeSound(const std::string& path);

/// Reads a WAV/FLAC file as a vibration recording: its sidecar (when present) over
/// `defaults`, the axes' channels scaled to m/s^2 (or left in file units when
/// uncalibrated), several axes reduced by DFT321 (whole-signal up to 2^21 frames, streamed
/// in 2^15-sample frames above). The condition stays 0 with labelled = false when unknown.
/// @throws InputError naming the file (or sidecar) and field: unreadable or truncated file,
/// fewer than 256 frames, a channel number out of range, a clipped channel (20 or more
/// samples at integer full scale), bad sidecar.
Recording ReadSoundRecording(const std::string& path, const SoundLabels& defaults = {});

}  // namespace hapticlab::modeling
