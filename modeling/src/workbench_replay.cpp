// Workbench replay: a measurement prepared for replay (decimated force samples, smoothed load
// and position, steady vibration windows with band powers), and `measurement check`.

#include "hapticlab/modeling/workbench_replay.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

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

}  // namespace

// ---------------------------------------------------------------------------------------------
Replay PrepareReplay(const Measurement& m, const ReplayOptions& o) {
  Replay r;
  r.file = m.file;
  r.block_s = o.block_s;
  r.position_resolution_m = o.position_resolution_m;
  // The position noise (SD) the adaptive smoothing below compares its windows with: measured
  // from the rows at rest, else a given resolution's quarter, else that of the 1 um default.
  double position_sigma_m = o.position_resolution_m > 0 ? 0.25 * o.position_resolution_m : 0.25e-6;
  if (!(o.position_resolution_m > 0)) {
    // Position noise from rows at rest in contact: the second difference of white noise has
    // variance 6 sigma^2, its median absolute value 0.6745 of its SD.
    std::vector<double> d2;
    for (std::size_t i = 1; i + 1 < m.rows.size(); ++i) {
      const auto &a = m.rows[i - 1], &b = m.rows[i], &c = m.rows[i + 1];
      if (b.v_mps.head<2>().norm() > 1e-3 || !(b.f_N.z() > o.contact_force_N)) continue;
      for (int k = 0; k < 2; ++k) d2.push_back(std::abs(a.p_m[k] - 2 * b.p_m[k] + c.p_m[k]));
    }
    r.position_resolution_m = 1e-6;
    if (d2.size() >= 200) {
      const double sigma = internal::NoiseSdFromSecondDifferences(std::move(d2));
      r.position_resolution_m = std::clamp(4 * sigma, 0.05e-6, 5e-6);
      position_sigma_m = 0.25 * r.position_resolution_m;
    }
  }
  if (m.rows.size() < 2) throw InputError(m.file, 0, "", "a measurement needs at least two rows");
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  double rate = 1.0 / dt[dt.size() / 2];
  if (std::abs(rate - std::round(rate)) < 1e-6 * rate)
    rate = std::round(rate);  // time stamps' rounding
  const int stride = std::max(1, static_cast<int>(std::lround(rate / o.max_force_rate_hz)));
  const auto half_load =
      static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.load_smoothing_s * rate)));
  const auto half_pos =
      static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.position_smoothing_s * rate)));
  if (!(o.position_resolution_m > 0) && half_pos >= 2) {
    // The smoothed positions' noise: the centre weight is the variance factor of the SG fit.
    const double hm = static_cast<double>(half_pos);
    r.position_resolution_m = std::max(
        0.05e-6, r.position_resolution_m * std::sqrt(3 * (3 * hm * hm + 3 * hm - 1) /
                                                     ((2 * hm - 1) * (2 * hm + 1) * (2 * hm + 3))));
  }
  // Candidate half-widths of the adaptive position smoothing: raw (0), then 2 rows and growing
  // by half up to the configured window.
  std::vector<std::size_t> pos_halves{0};
  for (std::size_t h = 2; half_pos >= 2; h = std::max(h + 1, h * 3 / 2)) {
    pos_halves.push_back(std::min(h, half_pos));
    if (h >= half_pos) break;
  }
  r.rate_hz = rate / stride;
  const double t0 = m.rows.front().t_s;
  double dir = 0;
  bool any = false;
  for (std::size_t i = 0; i < m.rows.size(); i += stride) {
    const auto& row = m.rows[i];
    Replay::Sample s{};
    s.t_s = row.t_s;
    s.x_m = row.p_m.x();
    s.y_m = row.p_m.y();
    if (o.position_adaptive) {
      const std::size_t h = IciHalfWidth(m, i, pos_halves, position_sigma_m);
      SmoothPosition(m, i, h, &s.x_m, &s.y_m);
    } else {
      SmoothPosition(m, i, half_pos, &s.x_m, &s.y_m);
    }
    s.d_m = std::max(0.0, -row.p_m.z());
    s.ddot_mps = -row.v_mps.z();
    s.vx_mps = row.v_mps.x();
    s.vy_mps = row.v_mps.y();
    s.speed_mps = std::hypot(s.vx_mps, s.vy_mps);
    if (s.speed_mps > 1e-3) dir = std::atan2(s.vy_mps, s.vx_mps);  // at rest: the last motion's
    s.dir_rad = dir;
    s.fn_N = row.f_N.z();
    {
      // Quadratic Savitzky-Golay smoothing (closed-form centre weights, hand-written: five lines)
      // where the whole window is in contact: a moving average would bias the load by
      // W^2 f''/24 wherever it curves (ends of strokes, pokes), a bias that friction's speed
      // terms absorb (mu_b +1.5 % on noise-free free-hand data). Elsewhere the mean of the rows
      // in contact.
      double sum = 0;
      int count = 0;
      const std::size_t lo = i >= half_load ? i - half_load : 0,
                        hi = std::min(m.rows.size() - 1, i + half_load);
      for (std::size_t k = lo; k <= hi; ++k)
        if (m.rows[k].f_N.z() > o.contact_force_N) sum += m.rows[k].f_N.z(), ++count;
      s.fload_N = count ? sum / count : s.fn_N;
      if (o.load_savgol)
        SavGol2(
            m, i, half_load, [](const MeasurementRow& w) { return w.f_N.z(); },
            [&](const MeasurementRow& w) { return w.f_N.z() > o.contact_force_N; }, &s.fload_N);
    }
    s.ftx_N = row.f_N.x();
    s.fty_N = row.f_N.y();
    s.contact = s.fn_N > o.contact_force_N;
    s.block = static_cast<int>(std::floor((row.t_s - t0) / o.block_s));
    s.row = static_cast<int>(i);
    s.recording = m.recording_ids.empty() ? 0 : m.recording_ids[i];
    if (s.contact) {
      if (!any) r.x_min = r.x_max = s.x_m, r.y_min = r.y_max = s.y_m;
      any = true;
      r.x_min = std::min(r.x_min, s.x_m), r.x_max = std::max(r.x_max, s.x_m);
      r.y_min = std::min(r.y_min, s.y_m), r.y_max = std::max(r.y_max, s.y_m);
    }
    r.mutable_samples().push_back(s);
  }
  if (!any)
    throw InputError(m.file, 0, "fz_N",
                     fmt::format("no sample in contact (fz_N > {} N)", o.contact_force_N));

  if (!m.has_acceleration) return r;
  r.has_vibration = true;
  r.acc_rate_hz = rate;
  int n = 64;
  while (n * 2 <= o.window_s * rate * 1.5) n *= 2;
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
    r.band_lo_hz.assign(o.band_edges_hz.begin(), o.band_edges_hz.end() - 1);
    r.band_hi_hz.assign(o.band_edges_hz.begin() + 1, o.band_edges_hz.end());
  } else {
    for (int b = 0; b < o.bands; ++b) {
      r.band_lo_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b) / o.bands));
      r.band_hi_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b + 1) / o.bands));
    }
  }
  const int nb = static_cast<int>(r.band_lo_hz.size());
  // Bins of each band (at least the nearest bin).
  std::vector<std::vector<int>> bins(nb);
  for (int b = 0; b < nb; ++b) {
    for (int k = 1; k < n / 2; ++k) {
      const double f = k * rate / n;
      if (f >= r.band_lo_hz[b] && f < r.band_hi_hz[b]) bins[b].push_back(k);
    }
    if (bins[b].empty())
      bins[b].push_back(std::clamp(
          static_cast<int>(std::lround(std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]) * n / rate)), 1,
          n / 2 - 1));
  }
  std::vector<double> win(n);
  double wss = 0;
  for (int k = 0; k < n; ++k) {
    win[k] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * k / n);
    wss += win[k] * win[k];
  }
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  static std::mutex plan_mutex;  // FFTW's planner is not thread-safe
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    plan = fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  }
  for (std::size_t w0 = 0; w0 + n <= m.rows.size(); w0 += n / 4) {
    double sp = 0, f = 0, mean = 0, wsum = 0, sp2 = 0, f2 = 0;
    std::array<double, 4> d{};
    bool contact = true;
    for (int k = 0; k < n; ++k) {
      const auto& row = m.rows[w0 + k];
      if (!(row.f_N.z() > o.contact_force_N)) contact = false;
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
    if (!contact || sp < o.min_speed_mps) continue;
    // A window across two concatenated recordings is no one condition.
    if (!m.recording_ids.empty() && m.recording_ids[w0] != m.recording_ids[w0 + n - 1]) continue;
    // Only steady windows: a spectrum is a property of a condition, not of a transition.
    const double sv = std::sqrt(std::max(0.0, sp2 / n - sp * sp)),
                 sf = std::sqrt(std::max(0.0, f2 / n - f * f));
    if (sv > o.max_variation * sp || sf > o.max_variation * f) continue;
    for (auto& x : d) x /= std::max(wsum, 1e-12);
    for (int k = 0; k < n; ++k) in[k] = (m.rows[w0 + k].acc_mps2 - mean) * win[k];
    fftw_execute(plan);
    Replay::Window w{};
    w.t_s = m.rows[w0].t_s;
    w.speed_mps = sp;
    w.force_N = f;
    w.dir = d;
    w.block = static_cast<int>(std::floor((m.rows[w0 + n / 2].t_s - t0) / o.block_s));
    w.recording = m.recording_ids.empty() ? 0 : m.recording_ids[w0];
    w.row0 = static_cast<int>(w0);
    w.rows = n;
    for (int b = 0; b < nb; ++b) {
      double p = 0;
      for (const int k : bins[b]) p += (out[k][0] * out[k][0] + out[k][1] * out[k][1]) / wss;
      w.band_power.push_back(std::max(p / static_cast<double>(bins[b].size()), 1e-300));
    }
    r.windows.push_back(std::move(w));
  }
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
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
