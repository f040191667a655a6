// Command-line labels for sound recordings, and `measurement check` of vibration-only files.
#include "sound_flags.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/sound_recording.hpp"

namespace hapticlab::cli {

void AddSoundFlags(CLI::App* cmd, SoundFlags& f) {
  const std::string g = "Sound files (WAV/FLAC; a sidecar NAME.toml overrides these)";
  cmd->add_option("--speed", f.speed_mps, "Scan speed [m/s] of sound recordings")->group(g);
  cmd->add_option("--force", f.force_N, "Normal force [N] of sound recordings")->group(g);
  cmd->add_flag("--unlabelled", f.unlabelled, "Sound recordings' condition is unknown")->group(g);
  cmd->add_option("--scale", f.scale_mps2,
                  "m/s^2 per unit sample (integer formats: per full scale)")
      ->group(g);
  cmd->add_flag("--uncalibrated", f.uncalibrated,
                "Sound recordings are in their own units (said in every output)")
      ->group(g);
  cmd->add_option("--axes", f.axes,
                  "Channels (from 1) of the x, y, z axes, e.g. 1,2,3 (reduced by DFT321) or 2")
      ->group(g);
}

modeling::SoundLabels Labels(const SoundFlags& f) {
  modeling::SoundLabels l;
  auto positive = [](double v, const char* flag) {
    if (std::isnan(v)) return std::optional<double>();
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(kCommandLine, 0, flag, "expected a positive number");
    return std::optional<double>(v);
  };
  l.speed_mps = positive(f.speed_mps, "--speed");
  l.force_N = positive(f.force_N, "--force");
  l.scale_mps2 = positive(f.scale_mps2, "--scale");
  l.unlabelled = f.unlabelled;
  l.uncalibrated = f.uncalibrated;
  if (!f.axes.empty()) {
    std::size_t a = 0;
    while (a <= f.axes.size()) {
      const auto b = std::min(f.axes.find(',', a), f.axes.size());
      const std::string part = f.axes.substr(a, b - a);
      char* end = nullptr;
      const long v = std::strtol(part.c_str(), &end, 10);
      if (part.empty() || *end != '\0' || v < 1 || v > 64)
        throw InputError(
            kCommandLine, 0, "--axes",
            "expected 1 to 3 channel numbers from 1, e.g. 1,2,3; got '" + f.axes + "'");
      l.axes.push_back(static_cast<int>(v));
      a = b + 1;
    }
    if (l.axes.size() > 3) throw InputError(kCommandLine, 0, "--axes", "at most 3 axes (x, y, z)");
  }
  if (l.unlabelled && (l.speed_mps || l.force_N))
    throw InputError(kCommandLine, 0, "--unlabelled", "together with --speed or --force");
  if (l.speed_mps.has_value() != l.force_N.has_value())
    throw InputError(kCommandLine, 0, l.speed_mps ? "--force" : "--speed",
                     "a condition needs both --speed and --force");
  if (l.uncalibrated && l.scale_mps2)
    throw InputError(kCommandLine, 0, "--uncalibrated", "together with --scale");
  return l;
}

std::string CalibrationNote(bool calibrated) {
  return calibrated ? "" : " (uncalibrated: acceleration in the recordings' own units)";
}

int CheckVibrationOnly(const std::string& file, const modeling::SoundLabels& labels, bool json) {
  const modeling::Recording r = modeling::LoadRecording(file, labels);
  std::string format = "measurement CSV v1, vibration only (t_s, acc_mps2)";
  if (modeling::IsSoundFile(file)) {
    const auto info = modeling::ProbeSound(file);
    format =
        fmt::format("{}, {} channel{}", info.format, info.channels, info.channels == 1 ? "" : "s");
  }
  double lo = HUGE_VAL, hi = -HUGE_VAL, ss = 0;
  for (const double v : r.acc) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    ss += v * v;
  }
  const double rms = std::sqrt(ss / static_cast<double>(r.acc.size()));
  const double duration = static_cast<double>(r.acc.size()) / r.rate_hz;
  const std::string unit = r.calibrated ? "m/s^2" : "file units (uncalibrated)";
  if (json) {
    nlohmann::json cond = nullptr;
    if (r.labelled) cond = {{"speed_mps", r.speed_mps}, {"force_N", r.force_N}};
    PrintJson(nlohmann::json{{"file", file},
                             {"kind", "vibration"},
                             {"format", format},
                             {"samples", r.acc.size()},
                             {"duration_s", duration},
                             {"rate_hz", r.rate_hz},
                             {"axes", r.channels},
                             {"reduction", r.channels > 1 ? "dft321" : "none"},
                             {"condition", cond},
                             {"calibrated", r.calibrated},
                             {"acc_range", {lo, hi}},
                             {"acc_rms", rms}});
    return kExitOk;
  }
  fmt::print("{}: vibration only ({}), {} samples, {:.3f} s at {:.1f} Hz\n", file, format,
             r.acc.size(), duration, r.rate_hz);
  fmt::print("  axes      {}{}\n", r.channels, r.channels > 1 ? " (reduced to one by DFT321)" : "");
  fmt::print("  condition {}\n", r.labelled
                                     ? fmt::format("{:.4g} m/s, {:.4g} N", r.speed_mps, r.force_N)
                                     : std::string("unlabelled"));
  fmt::print("  acc       {:+.6g} .. {:+.6g}, RMS {:.6g} {}\n", lo, hi, rms, unit);
  return kExitOk;
}

}  // namespace hapticlab::cli
