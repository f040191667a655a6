#include "hapticlab/modeling/vibration.hpp"

#include <fftw3.h>
#include <fmt/format.h>
#include <soxr.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <set>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/cross_validation.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/biquad.hpp"
#include "hapticlab/renderer/delaunay.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace hapticlab::modeling {
namespace {

std::mutex g_fftw_mu;  // FFTW's planner is not thread-safe

}  // namespace

std::vector<double> Resample(const std::vector<double>& x, double from_hz, double to_hz,
                             ResampleQuality q) {
  HL_REQUIRE(from_hz > 0 && to_hz > 0, "resample rates must be positive");
  if (from_hz == to_hz) return x;
  std::vector<double> out(
      static_cast<std::size_t>(std::ceil(static_cast<double>(x.size()) * to_hz / from_hz)) + 16);
  const unsigned long recipe = q == ResampleQuality::kBest      ? SOXR_VHQ
                               : q == ResampleQuality::kFastest ? SOXR_MQ
                                                                : SOXR_HQ;
  const soxr_io_spec_t io = soxr_io_spec(SOXR_FLOAT64_I, SOXR_FLOAT64_I);
  const soxr_quality_spec_t qs = soxr_quality_spec(recipe, 0);
  std::size_t done = 0;
  const soxr_error_t err = soxr_oneshot(from_hz, to_hz, 1, x.data(), x.size(), nullptr, out.data(),
                                        out.size(), &done, &io, &qs, nullptr);
  if (err) throw std::runtime_error(std::string("soxr: ") + err);
  out.resize(done);
  return out;
}

std::vector<double> BandLimit(const std::vector<double>& x, double fs, double lo, double hi) {
  std::vector<renderer::BiquadCoeffs> stages;
  if (lo > 0) stages.insert(stages.end(), 2, renderer::BiquadCoeffs::ButterworthHighPass(lo, fs));
  if (hi > 0 && hi < 0.5 * fs)
    stages.insert(stages.end(), 2, renderer::BiquadCoeffs::ButterworthLowPass(hi, fs));
  std::vector<double> y(x);
  for (int pass = 0; pass < 2; ++pass) {  // forward, then backward: zero phase
    for (const auto& c : stages) {
      renderer::Biquad b(c);
      for (auto& v : y) v = b.Step(v);
    }
    std::reverse(y.begin(), y.end());
  }
  return y;
}

namespace {

// The biased autocorrelation of x (mean removed) at lags 0..pmax, and the sample count.
struct Autocorr {
  std::vector<double> r;
  double n = 0;
};
Autocorr Autocorrelation(const std::vector<double>& x, int pmax) {
  const int n = static_cast<int>(x.size());
  HL_REQUIRE(pmax >= 1 && pmax <= renderer::kMaxArOrder, "AR order must be 1..64");
  if (n < 4 * pmax)
    throw InputError("", 0, "samples", fmt::format("{} samples are too few for order {}", n, pmax));
  double mean = 0;
  for (double v : x) mean += v;
  mean /= n;
  std::vector<double> xc(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) xc[i] = x[i] - mean;
  // Biased autocorrelation: the Toeplitz matrix is positive definite, so every reflection
  // coefficient has |k| < 1 and every fit is minimum phase.
  std::vector<double> r(static_cast<std::size_t>(pmax) + 1, 0.0);
  for (int lag = 0; lag <= pmax; ++lag) {
    double s = 0;
    for (int i = lag; i < n; ++i)
      s += xc[static_cast<std::size_t>(i)] * xc[static_cast<std::size_t>(i - lag)];
    r[static_cast<std::size_t>(lag)] = s / n;
  }
  return {r, static_cast<double>(n)};
}

// Several recordings of one condition pooled: their autocorrelations weighted by length (the
// autocorrelation of the recordings as one sample, without products across their seams), so
// the pooled Toeplitz matrix stays positive definite and the fit minimum phase.
Autocorr Pool(const std::vector<const Autocorr*>& parts) {
  Autocorr out{std::vector<double>(parts.front()->r.size(), 0.0), 0};
  for (const Autocorr* p : parts) {
    for (std::size_t k = 0; k < out.r.size(); ++k) out.r[k] += p->n * p->r[k];
    out.n += p->n;
  }
  for (auto& v : out.r) v /= out.n;
  return out;
}

// Levinson-Durbin on an autocorrelation for orders 1..pmax: every order's coefficients,
// prediction-error variance and criterion in one pass.
std::vector<ArFit> Levinson(const Autocorr& ac, int pmax, OrderCriterion criterion) {
  const std::vector<double>& r = ac.r;
  const double n = ac.n;
  if (!(r[0] > 0)) throw InputError("", 0, "samples", "the recording is constant");
  std::vector<double> a(static_cast<std::size_t>(pmax) + 1, 0.0), prev;
  double err = r[0];
  std::vector<ArFit> out;
  for (int m = 1; m <= pmax; ++m) {
    double acc = r[static_cast<std::size_t>(m)];
    for (int i = 1; i < m; ++i)
      acc -= a[static_cast<std::size_t>(i)] * r[static_cast<std::size_t>(m - i)];
    const double k = acc / err;
    prev = a;
    a[static_cast<std::size_t>(m)] = k;
    for (int i = 1; i < m; ++i)
      a[static_cast<std::size_t>(i)] =
          prev[static_cast<std::size_t>(i)] - k * prev[static_cast<std::size_t>(m - i)];
    err *= 1 - k * k;
    ArFit f;
    f.coeffs.assign(a.begin() + 1, a.begin() + m + 1);
    f.variance = err;
    f.order = m;
    f.criterion =
        n * std::log(err) + (criterion == OrderCriterion::kAic ? 2.0 * m : m * std::log(n));
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<ArFit> LevinsonAll(const std::vector<double>& x, int pmax, OrderCriterion criterion) {
  return Levinson(Autocorrelation(x, pmax), pmax, criterion);
}

}  // namespace

ArFit FitAr(const std::vector<double>& x, int order, int max_order, OrderCriterion criterion) {
  const auto all = LevinsonAll(x, order > 0 ? order : max_order, criterion);
  if (order > 0) return all.back();
  return *std::min_element(all.begin(), all.end(), [](const ArFit& a, const ArFit& b) {
    return a.criterion < b.criterion;
  });
}

std::vector<double> WelchMagnitude(const std::vector<double>& x, int segment) {
  if (segment < 16 || static_cast<std::size_t>(segment) > x.size())
    throw InputError("", 0, "samples",
                     "spectrum: the signal needs at least one segment of samples");
  const auto n = static_cast<std::size_t>(segment);
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i)
    w[i] = 0.5 -
           0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  fftw_plan plan;
  {
    std::lock_guard lock(g_fftw_mu);
    plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), in, out, FFTW_ESTIMATE);
  }
  std::vector<double> p(n / 2 + 1, 0.0);
  int segs = 0;
  for (std::size_t s0 = 0; s0 + n <= x.size(); s0 += n / 2, ++segs) {
    for (std::size_t i = 0; i < n; ++i) in[i] = w[i] * x[s0 + i];
    fftw_execute(plan);
    for (std::size_t k = 0; k < p.size(); ++k)
      p[k] += out[k][0] * out[k][0] + out[k][1] * out[k][1];
  }
  {
    std::lock_guard lock(g_fftw_mu);
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
  for (auto& v : p) v = std::sqrt(v / segs);
  return p;
}

double SpectralError(const std::vector<double>& a, const std::vector<double>& b, int segment) {
  const auto ma = WelchMagnitude(a, segment), mb = WelchMagnitude(b, segment);
  double num = 0, den = 0;
  for (std::size_t k = 0; k < ma.size(); ++k) {
    num += (ma[k] - mb[k]) * (ma[k] - mb[k]);
    den += ma[k] * ma[k];
  }
  if (!(den > 0)) throw InputError("", 0, "samples", "E_s: the measured signal has no energy");
  return std::sqrt(num / den);
}

AdfResult AugmentedDickeyFuller(const std::vector<double>& y, int max_lags) {
  const int T = static_cast<int>(y.size());
  if (T < 50) throw InputError("", 0, "samples", "ADF needs at least 50 samples");
  if (max_lags < 0) max_lags = static_cast<int>(std::floor(12 * std::pow(T / 100.0, 0.25)));
  std::vector<double> dy(static_cast<std::size_t>(T - 1));
  for (int t = 1; t < T; ++t)
    dy[static_cast<std::size_t>(t - 1)] =
        y[static_cast<std::size_t>(t)] - y[static_cast<std::size_t>(t - 1)];
  // Every lag order is fitted on the same sample (t = max_lags + 1 .. T - 1) so AICs compare.
  // The regressors of lag order p are the first 2 + p columns of the full design [1, y[-1],
  // dy[-1..-max_lags]], so one Householder QR of the full design (no pivoting) gives every
  // nested fit: R's leading k x k block and the first k entries of Q'z are those of the first k
  // columns, RSS_k = sum_{i>=k} (Q'z)_i^2 (one QR instead of max_lags + 1, which makes the
  // whole of a long recording affordable).
  const int n = T - 1 - max_lags, K = 2 + max_lags;
  Eigen::MatrixXd X(n, K);
  Eigen::VectorXd z(n);
  for (int i = 0; i < n; ++i) {
    const int t = max_lags + 1 + i;  // index into y; dy[t-1] = y[t] - y[t-1]
    z(i) = dy[static_cast<std::size_t>(t - 1)];
    X(i, 0) = 1.0;
    X(i, 1) = y[static_cast<std::size_t>(t - 1)];
    for (int j = 1; j <= max_lags; ++j) X(i, 1 + j) = dy[static_cast<std::size_t>(t - 1 - j)];
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(X);
  const Eigen::VectorXd qz = qr.householderQ().adjoint() * z;
  const Eigen::MatrixXd R = qr.matrixQR().topRows(K).triangularView<Eigen::Upper>();
  AdfResult best;
  double best_aic = std::numeric_limits<double>::infinity();
  std::vector<double> tail(static_cast<std::size_t>(K) + 1);  // tail[k] = sum_{i>=k} qz_i^2
  tail[static_cast<std::size_t>(K)] = qz.tail(n - K).squaredNorm();
  for (int i = K - 1; i >= 0; --i)
    tail[static_cast<std::size_t>(i)] = tail[static_cast<std::size_t>(i) + 1] + qz(i) * qz(i);
  for (int p = 0; p <= max_lags; ++p) {
    const int k = 2 + p;
    const double rss = tail[static_cast<std::size_t>(k)];
    const double aic = n * std::log(rss / n) + 2.0 * k;
    if (!(aic < best_aic)) continue;
    best_aic = aic;
    // gamma = beta(1); its variance s2 [(R_k'R_k)^-1](1,1) = s2 |row 1 of R_k^-1|^2.
    const auto Rk = R.topLeftCorner(k, k).triangularView<Eigen::Upper>();
    const Eigen::VectorXd beta = Rk.solve(qz.head(k));
    const Eigen::MatrixXd Rinv = Rk.solve(Eigen::MatrixXd::Identity(k, k));
    const double s2 = rss / (n - k);
    best.statistic = beta(1) / std::sqrt(s2 * Rinv.row(1).squaredNorm());
    best.lags = p;
  }
  // MacKinnon (2010), Table 2, constant and no trend, 5 %: beta_inf, beta_1, beta_2.
  const double nobs = n;
  best.critical_5pct = -2.86154 - 2.8903 / nobs - 4.234 / (nobs * nobs);
  best.rejects_unit_root = best.statistic < best.critical_5pct;
  return best;
}

CutoffResult StationarityCutoff(const std::vector<double>& x, double fs, double lo, double hi,
                                double step, std::size_t max_samples) {
  HL_REQUIRE(lo > 0 && hi >= lo && step > 0 && hi < 0.5 * fs,
             "cut-off range must satisfy 0 < lo <= hi < fs/2 and step > 0");
  CutoffResult r;
  const std::size_t used = max_samples == 0 ? x.size() : std::min(x.size(), max_samples);
  r.samples = used;
  const std::vector<double> part(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(used));
  for (double fc = lo; fc <= hi + 1e-9; fc += step) {
    const auto adf = AugmentedDickeyFuller(BandLimit(part, fs, fc, 0));
    r.tried.emplace_back(fc, adf);
    if (adf.rejects_unit_root) {
      r.found = true;
      r.cutoff_hz = fc;
      // Already at the lowest cut-off tried: the search range bounds f_c from above only.
      r.stationary_at_every_cutoff = r.tried.size() == 1;
      break;
    }
  }
  return r;
}

std::vector<double> Preprocess(const Recording& r, const VibrationFitOptions& o) {
  // Resource limit derived from the input: at most 8x upsampling, so the work and memory
  // stay proportional to the recording (a model rate of 1e9 Hz would otherwise ask for
  // gigabytes).
  // At most 64x downsampling too: soxr's filter for an extreme ratio (1e-6 Hz from 10 kHz)
  // runs for hours.
  constexpr double kMaxUpsampling = 8, kMaxDownsampling = 64;
  const double lo = std::max(r.rate_hz / kMaxDownsampling, 2 * std::max(0.0, o.band_lo_hz));
  if (!(o.model_rate_hz > lo) || !(o.model_rate_hz <= kMaxUpsampling * r.rate_hz))
    throw InputError(r.file, 0, "model_rate_hz",
                     fmt::format("model rate {} Hz must be in ({:g}, {:g}] Hz (at most {:g}x "
                                 "above or {:g}x below the recording's {:g} Hz, and above twice "
                                 "the band's low edge {:g} Hz)",
                                 o.model_rate_hz, lo, kMaxUpsampling * r.rate_hz, kMaxUpsampling,
                                 kMaxDownsampling, r.rate_hz, o.band_lo_hz));
  const auto y = Resample(r.acc, r.rate_hz, o.model_rate_hz, o.resample);
  return BandLimit(y, o.model_rate_hz, o.band_lo_hz, 0.475 * o.model_rate_hz);
}

namespace {

// Every recording's autocorrelation (preprocessed), in parallel over recordings; the first
// error is rethrown.
std::vector<Autocorr> Autocorrelations(const std::vector<Recording>& recs, int pmax,
                                       const VibrationFitOptions& o) {
  std::vector<Autocorr> acs(recs.size());
  const unsigned hw = o.threads > 0 ? static_cast<unsigned>(o.threads)
                                    : std::max(1u, std::thread::hardware_concurrency());
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mu;
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < recs.size();) {
      try {
        acs[i] = Autocorrelation(Preprocess(recs[i], o), pmax);
      } catch (...) {
        std::lock_guard lock(error_mu);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < std::min<std::size_t>(hw, recs.size()); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return acs;
}

}  // namespace

renderer::VibrationBank FitVibrationBank(const std::vector<Recording>& recs,
                                         const VibrationFitOptions& o) {
  HL_REQUIRE(!recs.empty(), "no recordings to fit");
  RequireConditions(recs, "fit-vibration");
  const int pmax = o.order > 0 ? o.order : o.max_order;
  const std::vector<Autocorr> acs = Autocorrelations(recs, pmax, o);
  // One fit per (speed, force) condition: the recordings of a condition pooled.
  std::map<std::pair<double, double>, std::vector<const Autocorr*>> by_condition;
  for (std::size_t i = 0; i < recs.size(); ++i)
    by_condition[{recs[i].speed_mps, recs[i].force_N}].push_back(&acs[i]);
  std::map<std::pair<double, double>, std::vector<ArFit>> fits;
  for (const auto& [cond, parts] : by_condition)
    fits[cond] = Levinson(Pool(parts), pmax, o.criterion);
  // One order for the whole bank (LSF interpolation needs equal orders): the criterion's
  // choice summed over the conditions.
  int order = o.order;
  if (order == 0) {
    double best = std::numeric_limits<double>::infinity();
    for (int p = 1; p <= pmax; ++p) {
      double total = 0;
      for (const auto& [cond, f] : fits) total += f[static_cast<std::size_t>(p - 1)].criterion;
      if (total < best) {
        best = total;
        order = p;
      }
    }
  }
  renderer::VibrationBank b;
  b.sample_rate_hz = o.model_rate_hz;
  std::set<double> speeds, forces;
  for (const auto& [cond, f] : fits) {
    speeds.insert(cond.first);
    forces.insert(cond.second);
  }
  auto cell = [&](const std::pair<double, double>& cond) {
    const ArFit& fit = fits.at(cond)[static_cast<std::size_t>(order - 1)];
    renderer::ArCell c;
    c.speed_mps = cond.first;
    c.force_N = cond.second;
    c.coeffs = fit.coeffs;
    c.variance = fit.variance;
    c.lsf = renderer::ArToLsf(c.coeffs);
    return c;
  };
  if (speeds.size() * forces.size() == fits.size()) {  // a full grid
    b.grid_speeds_mps.assign(speeds.begin(), speeds.end());
    b.grid_forces_N.assign(forces.begin(), forces.end());
    for (double v : speeds)
      for (double f : forces) b.cells.push_back(cell({v, f}));
  } else {
    std::vector<double> xs, ys;
    for (const auto& [cond, f] : fits) {
      b.cells.push_back(cell(cond));
      xs.push_back(cond.first);
      ys.push_back(cond.second);
    }
    if (fits.size() >= 3) b.triangles = renderer::DelaunayTriangulate(xs, ys);
  }
  return b;
}

CvResult CrossValidate(const std::vector<Recording>& recs, const std::vector<double>& tv,
                       const std::vector<double>& tf, const VibrationFitOptions& o,
                       std::uint64_t seed) {
  int order = 0;
  auto res = CrossValidateModel(
      recs, tv, tf, o,
      [&](const std::vector<Recording>& train) -> ConditionSynthesizer {
        auto interp = std::make_shared<renderer::VibrationInterpolator>(FitVibrationBank(train, o));
        order = interp->bank().order();
        return [interp](const Recording& r, std::size_t n, std::uint64_t s) {
          renderer::ArFilter f;
          interp->Interpolate(r.speed_mps, r.force_N, true, &f);
          f.active = true;  // synthesize even below the renderer's 1 cm/s switch-off
          renderer::ArSynth synth(s);
          std::vector<double> out(n);
          for (std::size_t k = 0; k < 4000; ++k) synth.Step(f);  // let the filter settle
          for (auto& v : out) v = synth.Step(f);
          return out;
        };
      },
      seed);
  res.order = order;
  return res;
}

}  // namespace hapticlab::modeling
