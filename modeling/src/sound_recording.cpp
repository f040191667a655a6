// Sound-file recordings (sound_recording.hpp): sidecars, libsndfile reading in blocks,
// DFT321 of several axes.
#include "hapticlab/modeling/sound_recording.hpp"

#include <fmt/format.h>
#include <sndfile.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/modeling/dft321.hpp"

namespace hapticlab::modeling {
namespace {

constexpr std::size_t kBlockFrames = 8192;         // frames read per libsndfile call
constexpr long long kWholeDft321Frames = 1 << 21;  // above: the streaming DFT321
constexpr int kClipRun = 20;                       // samples at full scale that mean clipping

struct SndCloser {
  void operator()(SNDFILE* f) const { sf_close(f); }
};
using SndPtr = std::unique_ptr<SNDFILE, SndCloser>;

std::string Lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Integer formats' bits (0 for float formats).
int IntegerBits(int format) {
  switch (format & SF_FORMAT_SUBMASK) {
    case SF_FORMAT_PCM_S8:
    case SF_FORMAT_PCM_U8:
      return 8;
    case SF_FORMAT_PCM_16:
      return 16;
    case SF_FORMAT_PCM_24:
      return 24;
    case SF_FORMAT_PCM_32:
      return 32;
    default:
      return 0;
  }
}

std::string FormatWords(int format) {
  const int major = format & SF_FORMAT_TYPEMASK, sub = format & SF_FORMAT_SUBMASK;
  const char* container = major == SF_FORMAT_FLAC                              ? "FLAC"
                          : major == SF_FORMAT_WAV || major == SF_FORMAT_WAVEX ? "WAV"
                          : major == SF_FORMAT_RF64                            ? "RF64"
                                                                               : "sound file";
  if (const int bits = IntegerBits(format)) return fmt::format("{}, {}-bit PCM", container, bits);
  if (sub == SF_FORMAT_FLOAT) return std::string(container) + ", 32-bit float";
  if (sub == SF_FORMAT_DOUBLE) return std::string(container) + ", 64-bit float";
  return container;
}

SndPtr Open(const std::string& path, SF_INFO* info) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, 0, "", "no such file");
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, info);
  if (!f)
    throw InputError(path, 0, "",
                     "not a readable WAV or FLAC file (damaged, truncated in its "
                     "header, or another format)");
  return SndPtr(f);
}

double PositiveNumber(const toml::node& v, const std::string& file, const std::string& key) {
  const auto d = v.value<double>();
  if (!d || !std::isfinite(*d) || !(*d > 0))
    throw InputError(file, static_cast<int>(v.source().begin.line), "recording." + key,
                     "expected a positive number");
  return *d;
}

std::string Word(const toml::node& v, const std::string& file, const std::string& key,
                 const std::set<std::string>& allowed) {
  const auto s = v.value<std::string>();
  if (!s || !allowed.count(*s)) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
    throw InputError(file, static_cast<int>(v.source().begin.line), "recording." + key,
                     "expected one of " + list);
  }
  return *s;
}

std::vector<int> Axes(const toml::node& v, const std::string& file) {
  const int line = static_cast<int>(v.source().begin.line);
  const auto* arr = v.as_array();
  std::vector<int> out;
  if (arr)
    for (const auto& e : *arr)
      if (const auto i = e.value<int64_t>(); i && *i >= 1 && *i <= 64)
        out.push_back(static_cast<int>(*i));
  if (!arr || out.size() != arr->size() || out.empty() || out.size() > 3)
    throw InputError(file, line, "recording.axes",
                     "expected 1 to 3 channel numbers (from 1), e.g. [1, 2, 3]");
  return out;
}

}  // namespace

bool IsSoundFile(const std::string& path) {
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  return ext == ".wav" || ext == ".flac";
}

std::string SidecarPath(const std::string& sound_path) {
  return std::filesystem::path(sound_path).replace_extension(".toml").string();
}

void CheckLabels(const SoundLabels& l, const std::string& file) {
  if (l.unlabelled && (l.speed_mps || l.force_N))
    throw InputError(file, 0, "condition", "\"unlabelled\" together with a speed or force");
  if (l.speed_mps.has_value() != l.force_N.has_value())
    throw InputError(file, 0, l.speed_mps ? "force_N" : "speed_mps",
                     "a condition needs both speed and force");
  if (l.uncalibrated && l.scale_mps2)
    throw InputError(file, 0, "scale_mps2", "a scale given for an uncalibrated recording");
}

SoundLabels ReadSoundSidecar(const std::string& path) {
  const toml::table doc = ParseTomlFile(path, "sidecar");
  SoundLabels l;
  const toml::table* t = doc["recording"].as_table();
  if (!t) throw InputError(path, 0, "recording", "missing [recording] table");
  for (const auto& [k, v] : doc)
    if (k.str() != "recording")
      throw InputError(path, static_cast<int>(v.source().begin.line), std::string(k.str()),
                       "unknown table or key; a sidecar holds one [recording] table");
  for (const auto& [k, v] : *t) {
    const std::string key(k.str());
    if (key == "speed_mps") {
      l.speed_mps = PositiveNumber(v, path, key);
    } else if (key == "force_N") {
      l.force_N = PositiveNumber(v, path, key);
    } else if (key == "condition") {
      l.unlabelled = Word(v, path, key, {"labelled", "unlabelled"}) == "unlabelled";
    } else if (key == "scale_mps2") {
      l.scale_mps2 = PositiveNumber(v, path, key);
    } else if (key == "calibration") {
      l.uncalibrated = Word(v, path, key, {"calibrated", "uncalibrated"}) == "uncalibrated";
    } else if (key == "axes") {
      l.axes = Axes(v, path);
    } else if (key == "material") {
      const auto s = v.value<std::string>();
      if (!s)
        throw InputError(path, static_cast<int>(v.source().begin.line), "recording.material",
                         "expected a string");
      l.material = *s;
    } else {
      throw InputError(path, static_cast<int>(v.source().begin.line), "recording." + key,
                       "unknown key; expected speed_mps, force_N, condition, scale_mps2, "
                       "calibration, axes or material");
    }
  }
  CheckLabels(l, path);
  if (l.scale_mps2 == std::nullopt && t->contains("calibration") && !l.uncalibrated)
    throw InputError(path, 0, "recording.scale_mps2", "calibration = \"calibrated\" needs it");
  return l;
}

SoundLabels MergeLabels(const SoundLabels& d, const SoundLabels& s) {
  SoundLabels m = d;
  if (s.speed_mps || s.unlabelled) {
    m.speed_mps = s.speed_mps;
    m.force_N = s.force_N;
    m.unlabelled = s.unlabelled;
  }
  if (s.scale_mps2 || s.uncalibrated) {
    m.scale_mps2 = s.scale_mps2;
    m.uncalibrated = s.uncalibrated;
  }
  if (!s.axes.empty()) m.axes = s.axes;
  if (!s.material.empty()) m.material = s.material;
  return m;
}

SoundInfo ProbeSound(const std::string& path) {
  SF_INFO info{};
  const SndPtr f = Open(path, &info);
  return {info.channels, static_cast<double>(info.samplerate), info.frames,
          FormatWords(info.format)};
}

namespace {

// Reads every frame in blocks: the chosen channels (0-based `cols`) reduced to one signal,
// and clipping counted per channel on integer formats.
std::vector<double> ReadAxes(SNDFILE* f, const SF_INFO& info, const std::vector<int>& cols,
                             const std::string& path) {
  const int bits = IntegerBits(info.format);
  // sf_readf_double normalises integers to [-1, 1): full scale is -1 or 1 - 2^(1-bits).
  const double top = bits ? 1.0 - std::ldexp(1.0, 1 - bits) : HUGE_VAL;
  const auto nch = static_cast<std::size_t>(info.channels);
  const std::size_t naxes = cols.size();
  const bool stream = naxes > 1 && info.frames > kWholeDft321Frames;
  std::vector<std::vector<double>> whole(stream ? 0 : naxes);
  std::unique_ptr<Dft321Stream> reducer;
  if (stream) reducer = std::make_unique<Dft321Stream>(static_cast<int>(naxes));
  std::vector<long long> clipped(naxes, 0);
  std::vector<double> block(kBlockFrames * nch);
  long long total = 0;
  for (;;) {
    const sf_count_t got = sf_readf_double(f, block.data(), static_cast<sf_count_t>(kBlockFrames));
    if (got <= 0) break;
    const auto n = static_cast<std::size_t>(got);
    for (std::size_t a = 0; a < naxes; ++a) {
      const auto c = static_cast<std::size_t>(cols[a]);
      for (std::size_t i = 0; i < n; ++i) {
        const double v = block[i * nch + c];
        if (!std::isfinite(v))
          throw InputError(
              path, 0, fmt::format("channel {}", c + 1),
              fmt::format("sample {} is not finite", total + static_cast<long long>(i)));
        clipped[a] += v >= top || v <= -1.0 ? (bits ? 1 : 0) : 0;
        if (!stream) whole[a].push_back(v);
      }
    }
    if (stream) reducer->Push(block.data(), n, static_cast<int>(nch), cols.data());
    total += got;
  }
  if (total < info.frames)
    throw InputError(path, 0, "frames",
                     fmt::format("truncated: the header announces {} frames, {} could be read",
                                 info.frames, total));
  for (std::size_t a = 0; a < naxes; ++a)
    if (clipped[a] >= kClipRun)
      throw InputError(
          path, 0, fmt::format("channel {}", cols[a] + 1),
          fmt::format("{} samples sit at full scale: the recording clipped", clipped[a]));
  if (stream) return reducer->Finish();
  return naxes == 1 ? std::move(whole[0]) : Dft321(whole);
}

// libsndfile opens a WAV whose data chunk runs past the end of the file and reads what is
// there; its log (never shown to the user) records "data : ANNOUNCED (should be FOUND)".
void CheckNotTruncated(SNDFILE* f, const std::string& path) {
  std::vector<char> log(16384, '\0');
  sf_command(f, SFC_GET_LOG_INFO, log.data(), static_cast<int>(log.size()) - 1);
  const std::string text(log.data());
  for (std::size_t at = 0; (at = text.find("data :", at)) != std::string::npos; ++at) {
    if (at > 0 && text[at - 1] != '\n') continue;
    long long announced = 0, found = 0;
    if (std::sscanf(text.c_str() + at, "data : %lld (should be %lld)", &announced, &found) == 2 &&
        announced > found)
      throw InputError(path, 0, "frames",
                       fmt::format("truncated: the header announces {} bytes of samples, the "
                                   "file holds {}",
                                   announced, found));
  }
}

}  // namespace

Recording ReadSoundRecording(const std::string& path, const SoundLabels& defaults) {
  SoundLabels l = defaults;
  const std::string side = SidecarPath(path);
  if (std::filesystem::exists(side)) l = MergeLabels(defaults, ReadSoundSidecar(side));
  SF_INFO info{};
  const SndPtr f = Open(path, &info);
  CheckNotTruncated(f.get(), path);
  if (info.channels < 1 || info.samplerate <= 0)
    throw InputError(path, 0, "", "the header gives no channels or no sample rate");
  std::vector<int> cols;
  if (l.axes.empty()) {
    if (info.channels != 1 && info.channels != 3)
      throw InputError(path, 0, "axes",
                       fmt::format("{} channels: say which are the x, y, z axes (axes = [..] in "
                                   "{}, or --axes)",
                                   info.channels, side));
    for (int c = 0; c < info.channels; ++c) cols.push_back(c);
  } else {
    for (const int a : l.axes) {
      if (a > info.channels)
        throw InputError(path, 0, "axes",
                         fmt::format("channel {} asked for, the file has {}", a, info.channels));
      cols.push_back(a - 1);
    }
  }
  Recording r;
  r.file = path;
  r.rate_hz = info.samplerate;
  r.channels = static_cast<int>(cols.size());
  r.acc = ReadAxes(f.get(), info, cols, path);
  if (r.acc.size() < 256)
    throw InputError(path, 0, "frames", "too short: at least 256 samples are needed");
  r.calibrated = l.scale_mps2.has_value() && !l.uncalibrated;
  if (r.calibrated)
    for (auto& v : r.acc) v *= *l.scale_mps2;
  r.labelled = l.speed_mps.has_value() && !l.unlabelled;
  if (r.labelled) {
    r.speed_mps = *l.speed_mps;
    r.force_N = *l.force_N;
  }
  return r;
}

}  // namespace hapticlab::modeling
