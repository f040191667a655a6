// Workbench replay: a measurement prepared for replay (decimated force samples, smoothed load
// and position, steady vibration windows with band powers), and `measurement check`.

#include "hapticlab/modeling/workbench_replay.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

// (workbench_internal.hpp; workbench_vibration.cpp picks a fixed model's bins the same way)
std::vector<std::vector<int>> internal::BandBins(const Replay& r, int n, double rate) {
  const std::size_t nb = r.band_lo_hz.size();
  std::vector<std::vector<int>> bins(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    for (int k = 1; k < n / 2; ++k) {
      const double f = k * rate / n;
      if (f >= r.band_lo_hz[b] && f < r.band_hi_hz[b]) bins[b].push_back(k);
    }
    if (bins[b].empty())
      bins[b].push_back(std::clamp(
          static_cast<int>(std::lround(std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]) * n / rate)), 1,
          n / 2 - 1));
  }
  return bins;
}

namespace {

// Centre value of a quadratic Savitzky-Golay fit over rows i-h..i+h into *out (closed-form
// weights (3 (3h^2 + 3h - 1) - 15 j^2) / ((2h-1)(2h+1)(2h+3)), hand-written: a few lines); false,
// *out untouched, where the window leaves the measurement or a row fails `use`.
template <class Value, class Use>
bool SavGol2(const Measurement& m, std::size_t i, std::size_t h, Value value, Use use,
             double* out) {
  if (h < 2 || i < h || i + h >= m.rows.size()) return false;
  const double hm = static_cast<double>(h);
  const double norm = (2 * hm - 1) * (2 * hm + 1) * (2 * hm + 3),
               c0 = 3 * (3 * hm * hm + 3 * hm - 1);
  double sg = 0;
  for (std::size_t k = i - h; k <= i + h; ++k) {
    if (!use(m.rows[k])) return false;
    const double j = static_cast<double>(k) - static_cast<double>(i);
    sg += (c0 - 15 * j * j) / norm * value(m.rows[k]);
  }
  *out = sg;
  return true;
}

// Variance factor of SavGol2's centre value over 2h+1 rows (1 for h < 2: the raw row).
double SavGol2Variance(std::size_t h) {
  if (h < 2) return 1;
  const double hm = static_cast<double>(h);
  return 3 * (3 * hm * hm + 3 * hm - 1) / ((2 * hm - 1) * (2 * hm + 1) * (2 * hm + 3));
}

// Positions x, y of row i by SavGol2 over half-width h (raw where h < 2 or the window leaves the
// measurement).
void SmoothPosition(const Measurement& m, std::size_t i, std::size_t h, double* x, double* y) {
  const auto all = [](const MeasurementRow&) { return true; };
  *x = m.rows[i].p_m.x();
  *y = m.rows[i].p_m.y();
  SavGol2(
      m, i, h, [](const MeasurementRow& w) { return w.p_m.x(); }, all, x);
  SavGol2(
      m, i, h, [](const MeasurementRow& w) { return w.p_m.y(); }, all, y);
}

// Locally adaptive window by the intersection of confidence intervals (LPA-ICI: Goldenshluger &
// Nemirovski 1997; Katkovnik 1999, IEEE Trans. Signal Process. 47(9)), hand-written (a dozen
// lines; no Debian library has it). Over the candidate half-widths, ascending, each estimate's
// interval value -+ kIciGamma sd (sd = sigma sqrt(variance factor)) is intersected with those
// of the shorter windows; the longest window whose intersection is not empty is kept, for both
// axes (the smaller of the two). At rest the longest window wins (its smoothing bias is below the
// noise); in fast or sharply curving motion a short one does, where the longest would shorten the
// path the Dahl bristle follows.
constexpr double kIciGamma = 2.0;  // ~ the two-sided 95 % normal quantile (not tuned)
std::size_t IciHalfWidth(const Measurement& m, std::size_t i,
                         const std::vector<std::size_t>& halves, double sigma) {
  std::size_t best = 0;
  for (int axis = 0; axis < 2; ++axis) {
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t keep = 0;
    for (const std::size_t h : halves) {
      double v = m.rows[i].p_m[axis];
      if (h >= 2 && !SavGol2(
                        m, i, h, [axis](const MeasurementRow& w) { return w.p_m[axis]; },
                        [](const MeasurementRow&) { return true; }, &v))
        break;
      const double sd = sigma * std::sqrt(SavGol2Variance(h));
      lo = std::max(lo, v - kIciGamma * sd);
      hi = std::min(hi, v + kIciGamma * sd);
      if (lo > hi) break;
      keep = h;
    }
    best = axis == 0 ? keep : std::min(best, keep);
  }
  return best;
}

// The position noise (SD) the adaptive smoothing compares its windows with: a given
// resolution's quarter; else measured from the rows at rest in contact, and *resolution_m set
// from it (1 um, SD 0.25 um, where too few rows rest). The second difference of white noise has
// variance 6 sigma^2, its median absolute value 0.6745 of its SD.
double PositionNoiseSd(const Measurement& m, const ReplayOptions& o, double* resolution_m) {
  if (o.position_resolution_m > 0) return 0.25 * o.position_resolution_m;
  std::vector<double> d2;
  for (std::size_t i = 1; i + 1 < m.rows.size(); ++i) {
    const auto &a = m.rows[i - 1], &b = m.rows[i], &c = m.rows[i + 1];
    if (b.v_mps.head<2>().norm() > 1e-3 || !(b.f_N.z() > o.contact_force_N)) continue;
    for (int k = 0; k < 2; ++k) d2.push_back(std::abs(a.p_m[k] - 2 * b.p_m[k] + c.p_m[k]));
  }
  *resolution_m = 1e-6;
  if (d2.size() < 200) return 0.25e-6;
  const double sigma = internal::NoiseSdFromSecondDifferences(std::move(d2));
  *resolution_m = std::clamp(4 * sigma, 0.05e-6, 5e-6);
  return 0.25 * *resolution_m;
}

// The measurement's rate: the inverse of the median time step, rounded to a whole number of
// Hz where it is one up to the time stamps' rounding.
double MeasurementRate(const Measurement& m) {
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  const double rate = 1.0 / dt[dt.size() / 2];
  return std::abs(rate - std::round(rate)) < 1e-6 * rate ? std::round(rate) : rate;
}

// How the force samples are taken from the rows: every `stride`-th row, the load smoothed over
// rows i -+ half_load, the position over i -+ half_pos (adaptively: one of pos_halves).
struct ForceSampling {
  int stride = 1;
  std::size_t half_load = 0, half_pos = 0;
  std::vector<std::size_t> pos_halves;  // raw (0), then 2 rows growing by half up to half_pos
  double position_sigma_m = 0;          // the noise the adaptive windows are compared with
  double contact_force_N = 0;
  bool position_adaptive = false, load_savgol = false;
};

ForceSampling ForceSamplingOf(double rate, const ReplayOptions& o, double position_sigma_m) {
  ForceSampling g;
  g.stride = std::max(1, static_cast<int>(std::lround(rate / o.max_force_rate_hz)));
  g.half_load =
      static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.load_smoothing_s * rate)));
  g.half_pos =
      static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.position_smoothing_s * rate)));
  g.pos_halves = {0};
  for (std::size_t h = 2; g.half_pos >= 2; h = std::max(h + 1, h * 3 / 2)) {
    g.pos_halves.push_back(std::min(h, g.half_pos));
    if (h >= g.half_pos) break;
  }
  g.position_sigma_m = position_sigma_m;
  g.contact_force_N = o.contact_force_N;
  g.position_adaptive = o.position_adaptive;
  g.load_savgol = o.load_savgol;
  return g;
}

// The load at row i: a quadratic Savitzky-Golay fit (closed-form centre weights, SavGol2) where
// the whole window is in contact: a moving average would bias the load by W^2 f''/24 wherever
// it curves (ends of strokes, pokes), a bias that friction's speed terms absorb (mu_b +1.5 % on
// noise-free free-hand data). Elsewhere the mean of the rows in contact (fn_N where none is).
double SmoothedLoad(const Measurement& m, std::size_t i, const ForceSampling& g, double fn_N) {
  double sum = 0;
  int count = 0;
  const std::size_t lo = i >= g.half_load ? i - g.half_load : 0,
                    hi = std::min(m.rows.size() - 1, i + g.half_load);
  for (std::size_t k = lo; k <= hi; ++k)
    if (m.rows[k].f_N.z() > g.contact_force_N) sum += m.rows[k].f_N.z(), ++count;
  double load_N = count ? sum / count : fn_N;
  if (g.load_savgol)
    SavGol2(
        m, i, g.half_load, [](const MeasurementRow& w) { return w.f_N.z(); },
        [&](const MeasurementRow& w) { return w.f_N.z() > g.contact_force_N; }, &load_N);
  return load_N;
}

// The force sample of row i (its direction of motion, dir_rad, is set by the caller: at rest it
// is the last motion's).
Replay::Sample ForceSample(const Measurement& m, std::size_t i, const ForceSampling& g, double t0,
                           double block_s) {
  const auto& row = m.rows[i];
  Replay::Sample s{};
  s.t_s = row.t_s;
  const std::size_t h =
      g.position_adaptive ? IciHalfWidth(m, i, g.pos_halves, g.position_sigma_m) : g.half_pos;
  SmoothPosition(m, i, h, &s.x_m, &s.y_m);
  s.d_m = std::max(0.0, -row.p_m.z());
  s.ddot_mps = -row.v_mps.z();
  s.vx_mps = row.v_mps.x();
  s.vy_mps = row.v_mps.y();
  s.speed_mps = std::hypot(s.vx_mps, s.vy_mps);
  s.fn_N = row.f_N.z();
  s.fload_N = SmoothedLoad(m, i, g, s.fn_N);
  s.ftx_N = row.f_N.x();
  s.fty_N = row.f_N.y();
  s.contact = s.fn_N > g.contact_force_N;
  s.block = static_cast<int>(std::floor((row.t_s - t0) / block_s));
  s.row = static_cast<int>(i);
  s.recording = m.recording_ids.empty() ? 0 : m.recording_ids[i];
  return s;
}

// Every stride-th row as a force sample; the extent of the samples in contact into r's
// x/y_min/max. Throws InputError where no sample is in contact.
void AddForceSamples(const Measurement& m, const ForceSampling& g, Replay* r) {
  const double t0 = m.rows.front().t_s;
  double dir = 0;
  bool any = false;
  for (std::size_t i = 0; i < m.rows.size(); i += g.stride) {
    Replay::Sample s = ForceSample(m, i, g, t0, r->block_s);
    if (s.speed_mps > 1e-3) dir = std::atan2(s.vy_mps, s.vx_mps);  // at rest: the last motion's
    s.dir_rad = dir;
    if (s.contact) {
      if (!any) r->x_min = r->x_max = s.x_m, r->y_min = r->y_max = s.y_m;
      any = true;
      r->x_min = std::min(r->x_min, s.x_m), r->x_max = std::max(r->x_max, s.x_m);
      r->y_min = std::min(r->y_min, s.y_m), r->y_max = std::max(r->y_max, s.y_m);
    }
    r->mutable_samples().push_back(s);
  }
  if (!any)
    throw InputError(m.file, 0, "fz_N",
                     fmt::format("no sample in contact (fz_N > {} N)", g.contact_force_N));
}

// The analysis bands into r: a model's explicit edges (InputError where they pass the
// measurement's Nyquist frequency), else `bands` log-spaced from 20 Hz to min(1000 Hz,
// 0.45 rate, max_band_hz).
void SetBands(const Measurement& m, const ReplayOptions& o, double rate, Replay* r) {
  double fmax = std::min(1000.0, 0.45 * rate);
  if (o.max_band_hz > 0) fmax = std::min(fmax, o.max_band_hz);
  if (!o.band_edges_hz.empty()) {
    if (o.band_edges_hz.back() > 0.5 * rate)
      throw InputError(
          m.file, 0, "acc_mps2",
          fmt::format(
              "the model's vibration bands reach {:.0f} Hz, above this measurement's Nyquist "
              "frequency {:.0f} Hz",
              o.band_edges_hz.back(), 0.5 * rate));
    r->band_lo_hz.assign(o.band_edges_hz.begin(), o.band_edges_hz.end() - 1);
    r->band_hi_hz.assign(o.band_edges_hz.begin() + 1, o.band_edges_hz.end());
    return;
  }
  for (int b = 0; b < o.bands; ++b) {
    r->band_lo_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b) / o.bands));
    r->band_hi_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b + 1) / o.bands));
  }
}

// The motion over one window of n rows from w0: mean speed and load, their SDs, the mean
// acceleration, the speed-weighted direction moments (cos, sin of the angle and of twice it)
// and whether every row is in contact.
struct WindowMotion {
  double speed_mps = 0, force_N = 0, mean_acc_mps2 = 0, speed_sd_mps = 0, force_sd_N = 0;
  std::array<double, 4> dir{};
  bool contact = true;
};

WindowMotion MeasureWindow(const Measurement& m, std::size_t w0, int n, double contact_force_N) {
  WindowMotion w;
  double sp = 0, f = 0, mean = 0, wsum = 0, sp2 = 0, f2 = 0;
  auto& d = w.dir;
  for (int k = 0; k < n; ++k) {
    const auto& row = m.rows[w0 + k];
    if (!(row.f_N.z() > contact_force_N)) w.contact = false;
    const double v = row.v_mps.head<2>().norm();
    sp += v, sp2 += v * v;
    f += row.f_N.z(), f2 += row.f_N.z() * row.f_N.z();
    mean += row.acc_mps2;
    if (v > 1e-4) {
      const double ph = std::atan2(row.v_mps.y(), row.v_mps.x());
      d[0] += v * std::cos(ph), d[1] += v * std::sin(ph), d[2] += v * std::cos(2 * ph),
          d[3] += v * std::sin(2 * ph);
      wsum += v;
    }
  }
  sp /= n, f /= n, mean /= n;
  w.speed_mps = sp;
  w.force_N = f;
  w.mean_acc_mps2 = mean;
  w.speed_sd_mps = std::sqrt(std::max(0.0, sp2 / n - sp * sp));
  w.force_sd_N = std::sqrt(std::max(0.0, f2 / n - f * f));
  for (auto& x : d) x /= std::max(wsum, 1e-12);
  return w;
}

// Whether the window from w0 is scored: in contact, fast enough, within one recording (a window
// across two concatenated recordings is no one condition) and steady (a spectrum is a property
// of a condition, not of a transition).
bool Scored(const Measurement& m, std::size_t w0, int n, const WindowMotion& w,
            const ReplayOptions& o) {
  if (!w.contact || w.speed_mps < o.min_speed_mps) return false;
  if (!m.recording_ids.empty() && m.recording_ids[w0] != m.recording_ids[w0 + n - 1]) return false;
  return !(w.speed_sd_mps > o.max_variation * w.speed_mps ||
           w.force_sd_N > o.max_variation * w.force_N);
}

std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;  // FFTW's planner is not thread-safe
  return mutex;
}

// The Hann-windowed periodogram of n rows of acceleration, |X_k|^2 / sum w^2, on one FFTW plan.
class HannPeriodogram {
 public:
  explicit HannPeriodogram(int n)
      : n_(n), win_(n), in_(fftw_alloc_real(n)), out_(fftw_alloc_complex(n / 2 + 1)) {
    for (int k = 0; k < n; ++k) {
      win_[k] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * k / n);
      wss_ += win_[k] * win_[k];
    }
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    plan_ = fftw_plan_dft_r2c_1d(n, in_, out_, FFTW_ESTIMATE);
  }
  ~HannPeriodogram() {
    {
      std::lock_guard<std::mutex> lock(FftwPlannerMutex());
      fftw_destroy_plan(plan_);
    }
    fftw_free(in_);
    fftw_free(out_);
  }
  HannPeriodogram(const HannPeriodogram&) = delete;
  HannPeriodogram& operator=(const HannPeriodogram&) = delete;

  // The rows w0 .. w0+n-1's acceleration less `mean`, transformed.
  void Transform(const Measurement& m, std::size_t w0, double mean) {
    for (int k = 0; k < n_; ++k) in_[k] = (m.rows[w0 + k].acc_mps2 - mean) * win_[k];
    fftw_execute(plan_);
  }
  // Bin k's power of the last transform.
  double Power(int k) const { return (out_[k][0] * out_[k][0] + out_[k][1] * out_[k][1]) / wss_; }

 private:
  int n_;
  std::vector<double> win_;
  double wss_ = 0;
  double* in_;
  fftw_complex* out_;
  fftw_plan plan_ = nullptr;
};

// The steady vibration windows (n rows, a power of two near window_s, every n/4 rows) with the
// mean periodogram power of each band into r.
void AddVibrationWindows(const Measurement& m, const ReplayOptions& o, double rate, Replay* r) {
  r->has_vibration = true;
  r->acc_rate_hz = rate;
  int n = 64;
  while (n * 2 <= o.window_s * rate * 1.5) n *= 2;
  SetBands(m, o, rate, r);
  const auto bins = internal::BandBins(*r, n, rate);
  const double t0 = m.rows.front().t_s;
  HannPeriodogram periodogram(n);
  for (std::size_t w0 = 0; w0 + n <= m.rows.size(); w0 += n / 4) {
    const WindowMotion motion = MeasureWindow(m, w0, n, o.contact_force_N);
    if (!Scored(m, w0, n, motion, o)) continue;
    periodogram.Transform(m, w0, motion.mean_acc_mps2);
    Replay::Window w{};
    w.t_s = m.rows[w0].t_s;
    w.speed_mps = motion.speed_mps;
    w.force_N = motion.force_N;
    w.dir = motion.dir;
    w.block = static_cast<int>(std::floor((m.rows[w0 + n / 2].t_s - t0) / o.block_s));
    w.recording = m.recording_ids.empty() ? 0 : m.recording_ids[w0];
    w.row0 = static_cast<int>(w0);
    w.rows = n;
    for (const auto& band : bins) {
      double p = 0;
      for (const int k : band) p += periodogram.Power(k);
      w.band_power.push_back(std::max(p / static_cast<double>(band.size()), 1e-300));
    }
    r->windows.push_back(std::move(w));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
Replay PrepareReplay(const Measurement& m, const ReplayOptions& o) {
  Replay r;
  r.file = m.file;
  r.block_s = o.block_s;
  r.position_resolution_m = o.position_resolution_m;
  const double position_sigma_m = PositionNoiseSd(m, o, &r.position_resolution_m);
  if (m.rows.size() < 2) throw InputError(m.file, 0, "", "a measurement needs at least two rows");
  const double rate = MeasurementRate(m);
  const ForceSampling g = ForceSamplingOf(rate, o, position_sigma_m);
  // The smoothed positions' noise: the centre weight is the variance factor of the SG fit.
  if (!(o.position_resolution_m > 0) && g.half_pos >= 2)
    r.position_resolution_m =
        std::max(0.05e-6, r.position_resolution_m * std::sqrt(SavGol2Variance(g.half_pos)));
  r.rate_hz = rate / g.stride;
  AddForceSamples(m, g, &r);
  if (m.has_acceleration) AddVibrationWindows(m, o, rate, &r);
  return r;
}

// ---------------------------------------------------------------------------------------------
MeasurementSummary Summarize(const Measurement& m) {
  MeasurementSummary s;
  s.samples = static_cast<int>(m.rows.size());
  if (m.rows.size() < 2) {
    s.warnings.push_back("fewer than two rows");
    return s;
  }
  s.duration_s = m.rows.back().t_s - m.rows.front().t_s;
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  auto sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double med = sorted[sorted.size() / 2];
  s.rate_hz = 1 / med;
  for (std::size_t i = 0; i < dt.size(); ++i) {
    s.max_gap_s = std::max(s.max_gap_s, dt[i]);
    if (dt[i] > 1.5 * med) {
      if (s.gaps < 5)
        s.warnings.push_back(fmt::format("line {}: gap of {:.4g} s ({:.1f} sample periods)",
                                         m.row_lines[i + 1], dt[i], dt[i] / med));
      ++s.gaps;
    }
  }
  const char* names[] = {"x_m",    "y_m",  "z_m",  "vx_mps", "vy_mps",
                         "vz_mps", "fx_N", "fy_N", "fz_N",   "acc_mps2"};
  for (const auto& r : m.rows) {
    const double v[] = {r.p_m.x(),   r.p_m.y(), r.p_m.z(), r.v_mps.x(), r.v_mps.y(),
                        r.v_mps.z(), r.f_N.x(), r.f_N.y(), r.f_N.z(),   r.acc_mps2};
    for (int k = 0; k < (m.has_acceleration ? 10 : 9); ++k) {
      auto [it, fresh] = s.ranges.try_emplace(names[k], v[k], v[k]);
      if (!fresh)
        it->second.first = std::min(it->second.first, v[k]),
        it->second.second = std::max(it->second.second, v[k]);
    }
    s.contact_samples += r.f_N.z() > 0.02;
  }
  if (s.contact_samples == 0) s.warnings.push_back("no sample in contact (fz_N > 0.02 N)");
  if (!m.has_acceleration)
    s.warnings.push_back("no acc_mps2 column: the vibration channel cannot be compared");
  else if (s.rate_hz < 2000)
    s.warnings.push_back(fmt::format("rate {:.0f} Hz: vibration above {:.0f} Hz is not measured",
                                     s.rate_hz, s.rate_hz / 2));
  if (s.ranges.count("fz_N") && s.ranges["fz_N"].second > 10)
    s.warnings.push_back(
        "fz_N exceeds 10 N: check the sign convention (force of the surface on the tool, +z)");
  return s;
}

}  // namespace hapticlab::modeling::wb
