// Reading vibration recordings (vibration_recording.hpp): one condition per file, or the
// steady parts of a free scan.
#include "hapticlab/modeling/vibration_recording.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/sound_recording.hpp"

namespace hapticlab::modeling {
namespace {

double MetaNumber(const Measurement& m, const char* key, double def) {
  const auto it = m.metadata.find(key);
  if (it == m.metadata.end()) return def;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || !std::isfinite(v))
    throw InputError(m.file, 0, key, "metadata is not a number: '" + it->second + "'");
  return v;
}

// The sample rate of a recording (its metadata's, else 1 / the median sample period); a gap of
// more than 1.5 periods is refused.
double UniformRate(const Measurement& m, const std::string& path) {
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  std::vector<double> sorted(dt);
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double med = sorted[sorted.size() / 2];
  const double rate_hz = MetaNumber(m, "rate_hz", 1.0 / med);
  for (std::size_t i = 0; i < dt.size(); ++i)
    if (dt[i] > 1.5 / rate_hz)
      throw InputError(path, m.row_lines[i + 1], "t_s",
                       fmt::format("gap of {:.3g} s in the recording (sample period {:.3g} s)",
                                   dt[i], 1.0 / rate_hz));
  return rate_hz;
}

// The acceleration column; refused when the sensor clipped (20 or more samples at an extreme
// value).
std::vector<double> UnclippedAcceleration(const Measurement& m, const std::string& path) {
  std::vector<double> acc;
  double lo = 1e300, hi = -1e300;
  for (const auto& row : m.rows) {
    acc.push_back(row.acc_mps2);
    lo = std::min(lo, row.acc_mps2);
    hi = std::max(hi, row.acc_mps2);
  }
  // Clipping: a long run of samples pinned at the extreme value.
  for (const double ext : {lo, hi}) {
    int run = 0, worst = 0;
    for (double a : acc) {
      run = a == ext ? run + 1 : 0;
      worst = std::max(worst, run);
    }
    int count = 0;
    for (double a : acc) count += a == ext;
    if (count >= 20 && hi > lo)
      throw InputError(path, 0, "acc_mps2",
                       fmt::format("{} samples sit at the extreme value {:.4g}: the sensor clipped",
                                   count, ext));
  }
  return acc;
}

// The condition of a steady scan from its rows: mean tangential speed and normal force, each
// with a coefficient of variation of at most 25 %.
void SteadyCondition(const Measurement& m, const std::string& path, Recording* r) {
  if (!m.has_forces)
    throw InputError(path, 0, "force_N", "no '# force_N:' metadata and no force columns");
  std::vector<double> v, f;
  for (const auto& row : m.rows) {
    v.push_back(row.v_mps.head<2>().norm());
    f.push_back(std::abs(row.f_N.z()));
  }
  auto mean_cv = [](const std::vector<double>& x) {
    double s = 0, s2 = 0;
    for (double a : x) s += a;
    const double mean = s / static_cast<double>(x.size());
    for (double a : x) s2 += (a - mean) * (a - mean);
    return std::pair{mean, std::sqrt(s2 / static_cast<double>(x.size())) / std::max(mean, 1e-12)};
  };
  const auto [vm, vcv] = mean_cv(v);
  const auto [fm, fcv] = mean_cv(f);
  if (vcv > 0.25 || fcv > 0.25)
    throw InputError(path, 0, vcv > 0.25 ? "speed" : "force",
                     "not a steady scan (coefficient of variation above 25 %): add '# speed_mps:' "
                     "and '# force_N:' metadata or cut the file to its steady part");
  r->speed_mps = vm;
  r->force_N = fm;
}

}  // namespace

Recording LoadRecording(const std::string& path, const SoundLabels& labels) {
  if (IsSoundFile(path)) return ReadSoundRecording(path, labels);
  const Measurement m =
      ReadMeasurementCsv(path, {.kinematics_only = true, .allow_vibration_only = true});
  if (!m.has_acceleration)
    throw InputError(path, 0, "acc_mps2", "column is missing: a vibration recording needs it");
  if (m.rows.size() < 256)
    throw InputError(path, 0, "", "too short: at least 256 samples are needed");
  Recording r;
  r.file = path;
  r.rate_hz = UniformRate(m, path);
  r.acc = UnclippedAcceleration(m, path);
  if (const auto it = m.metadata.find("calibration"); it != m.metadata.end()) {
    if (it->second != "uncalibrated" && it->second != "calibrated")
      throw InputError(path, 0, "calibration",
                       "expected 'calibrated' or 'uncalibrated', got '" + it->second + "'");
    r.calibrated = it->second == "calibrated";
  }
  // Condition: metadata, or steady per-row kinematics and force; unknown for a vibration-only
  // file without metadata.
  const bool meta = m.metadata.count("speed_mps") && m.metadata.count("force_N");
  if (!meta && !m.has_kinematics) {
    r.labelled = false;
    return r;
  }
  if (meta) {
    r.speed_mps = MetaNumber(m, "speed_mps", 0);
    r.force_N = MetaNumber(m, "force_N", 0);
  } else {
    SteadyCondition(m, path, &r);
  }
  if (!(r.speed_mps > 0) || !(r.force_N > 0))
    throw InputError(path, 0, "speed_mps", "speed and force of the condition must be positive");
  return r;
}

std::vector<Recording> LoadRecordingSegments(const std::string& path, double min_s,
                                             const SoundLabels& labels) {
  if (IsSoundFile(path)) return {ReadSoundRecording(path, labels)};
  const Measurement m =
      ReadMeasurementCsv(path, {.kinematics_only = true, .allow_vibration_only = true});
  if ((m.metadata.count("speed_mps") && m.metadata.count("force_N")) || !m.has_kinematics)
    return {LoadRecording(path)};
  if (!m.has_acceleration)
    throw InputError(path, 0, "acc_mps2", "column is missing: a vibration recording needs it");
  if (!m.has_forces)
    throw InputError(path, 0, "force_N", "no '# force_N:' metadata and no force columns");
  if (m.rows.size() < 256)
    throw InputError(path, 0, "", "too short: at least 256 samples are needed");
  const double rate = MetaNumber(
      m, "rate_hz",
      (static_cast<double>(m.rows.size()) - 1) / (m.rows.back().t_s - m.rows.front().t_s));
  const auto block = std::max<std::size_t>(16, static_cast<std::size_t>(0.25 * rate));
  struct Block {
    std::size_t begin, end;
    double v, f;
  };
  std::vector<Block> blocks;
  for (std::size_t b = 0; b + block <= m.rows.size(); b += block) {
    double v = 0, f = 0;
    for (std::size_t i = b; i < b + block; ++i) {
      v += m.rows[i].v_mps.head<2>().norm();
      f += std::abs(m.rows[i].f_N.z());
    }
    blocks.push_back(
        {b, b + block, v / static_cast<double>(block), f / static_cast<double>(block)});
  }
  std::vector<Recording> out;
  for (std::size_t g = 0; g < blocks.size();) {
    std::size_t e = g + 1;
    auto close = [](double a, double ref) {
      return std::abs(a - ref) <= 0.15 * std::max(ref, 1e-9);
    };
    while (e < blocks.size() && close(blocks[e].v, blocks[g].v) && close(blocks[e].f, blocks[g].f))
      ++e;
    const double dur = static_cast<double>(blocks[e - 1].end - blocks[g].begin) / rate;
    if (dur >= min_s && blocks[g].v > 0 && blocks[g].f > 0) {
      Recording r;
      r.file = fmt::format("{} [{:.2f}-{:.2f} s]", path, m.rows[blocks[g].begin].t_s,
                           m.rows[blocks[e - 1].end - 1].t_s);
      r.rate_hz = rate;
      double v = 0, f = 0;
      for (std::size_t i = blocks[g].begin; i < blocks[e - 1].end; ++i) {
        r.acc.push_back(m.rows[i].acc_mps2);
        v += m.rows[i].v_mps.head<2>().norm();
        f += std::abs(m.rows[i].f_N.z());
      }
      r.speed_mps = v / static_cast<double>(r.acc.size());
      r.force_N = f / static_cast<double>(r.acc.size());
      out.push_back(std::move(r));
    }
    g = e;
  }
  if (out.empty())
    throw InputError(
        path, 0, "speed",
        fmt::format("no steady part of at least {:.1f} s (speed and force within 15 %)", min_s));
  return out;
}

std::vector<Recording> LoadRecordings(const std::string& dir, const SoundLabels& labels) {
  namespace fs = std::filesystem;
  std::error_code ec;  // a name too long to look up is "not a folder", not a filesystem_error
  if (!fs::is_directory(dir, ec)) throw InputError(dir, 0, "recordings", "not a folder");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".csv" || IsSoundFile(e.path().string()))
      files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty())
    throw InputError(dir, 0, "recordings", "no .csv, .wav or .flac recordings in the folder");
  std::vector<Recording> out;
  Diagnostics d;
  for (const auto& f : files) {
    try {
      for (auto& r : LoadRecordingSegments(f, 1.0, labels)) out.push_back(std::move(r));
    } catch (const InputError& e) {
      for (const auto& x : e.diagnostics()) d.Add(x.file, x.line, x.field, x.message);
    }
  }
  d.ThrowIfAny();
  return out;
}

void RequireConditions(const std::vector<Recording>& recs, const std::string& command) {
  Diagnostics d;
  for (const auto& r : recs)
    if (!r.labelled)
      d.Add(r.file, 0, "speed_mps",
            command +
                " needs the scan condition, and this recording has none: give speed_mps and "
                "force_N (in a sidecar NAME.toml or '# speed_mps:'/'# force_N:' metadata) or "
                "--speed and --force");
  d.ThrowIfAny();
}

std::vector<Recording> PoolByCondition(const std::vector<Recording>& recs) {
  std::vector<Recording> out;
  for (const auto& r : recs) {
    auto same = std::find_if(out.begin(), out.end(), [&](const Recording& o) {
      return o.labelled && r.labelled && o.speed_mps == r.speed_mps && o.force_N == r.force_N;
    });
    if (same == out.end()) {
      out.push_back(r);
      continue;
    }
    if (same->rate_hz != r.rate_hz)
      throw InputError(r.file, 0, "rate_hz",
                       fmt::format("pooled with {} at {} Hz, but recorded at {} Hz; resample "
                                   "one of them",
                                   same->file, same->rate_hz, r.rate_hz));
    same->file += " + " + r.file;
    same->acc.insert(same->acc.end(), r.acc.begin(), r.acc.end());
    same->calibrated = same->calibrated && r.calibrated;
  }
  return out;
}

bool AllCalibrated(const std::vector<Recording>& recs) {
  return std::all_of(recs.begin(), recs.end(), [](const Recording& r) { return r.calibrated; });
}

}  // namespace hapticlab::modeling
