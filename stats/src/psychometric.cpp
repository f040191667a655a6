#include "hapticlab/stats/psychometric.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::stats {
namespace {

using psychophysics::Shape;

// Clamp probabilities away from 0 and 1 so a log-likelihood stays finite while iterating.
constexpr double kProbFloor = 1e-300;

struct Eval {
  double ll = 0;                     // log-likelihood without the binomial coefficients
  double g0 = 0, g1 = 0;             // gradient in (a, b)
  double i00 = 0, i01 = 0, i11 = 0;  // expected (Fisher) information
};

Eval Evaluate(const PsychometricData& d, const std::vector<double>& gx, Shape s, double guess,
              double lapse, double a, double b) {
  Eval e;
  const double span = 1 - guess - lapse;
  for (std::size_t i = 0; i < gx.size(); ++i) {
    const double eta = a + b * gx[i];
    const double F = psychophysics::CoreOfEta(s, eta);
    const double p = std::clamp(guess + span * F, kProbFloor, 1 - 1e-16);
    const double dp = span * psychophysics::CoreDensityOfEta(s, eta);
    const double n = d.n[i], k = d.k[i];
    e.ll += (k > 0 ? k * std::log(p) : 0) + (n - k > 0 ? (n - k) * std::log1p(-p) : 0);
    const double v = p * (1 - p);
    const double u = (k - n * p) * dp / v;
    const double w = n * dp * dp / v;
    e.g0 += u;
    e.g1 += u * gx[i];
    e.i00 += w;
    e.i01 += w * gx[i];
    e.i11 += w * gx[i] * gx[i];
  }
  return e;
}

// The saturated model's log-likelihood without the binomial coefficients (k/n per bin).
double SaturatedLogLik(const PsychometricData& d) {
  double s = 0;
  for (std::size_t i = 0; i < d.n.size(); ++i) {
    const double n = d.n[i], k = d.k[i];
    if (k > 0) s += k * std::log(k / n);
    if (n - k > 0) s += (n - k) * std::log((n - k) / n);
  }
  return s;
}

double LogChooseSum(const PsychometricData& d) {
  double s = 0;
  for (std::size_t i = 0; i < d.n.size(); ++i)
    s += std::lgamma(d.n[i] + 1.0) - std::lgamma(d.k[i] + 1.0) - std::lgamma(d.n[i] - d.k[i] + 1.0);
  return s;
}

// Starting values: weighted least squares of the transformed, slightly shrunk proportions.
void StartValues(const PsychometricData& d, const std::vector<double>& gx, Shape s, double guess,
                 double lapse, double* a, double* b) {
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < gx.size(); ++i) {
    const double p = (d.k[i] + 0.5) / (d.n[i] + 1.0);
    const double F = std::clamp((p - guess) / (1 - guess - lapse), 0.02, 0.98);
    const double y = psychophysics::EtaOfCore(s, F), w = d.n[i];
    sw += w, sx += w * gx[i], sy += w * y, sxx += w * gx[i] * gx[i], sxy += w * gx[i] * y;
  }
  const double var = sxx - sx * sx / sw;
  *b = var > 0 ? (sxy - sx * sy / sw) / var : 0;
  if (!(std::abs(*b) > 0) || !std::isfinite(*b)) {
    const auto [lo, hi] = std::minmax_element(gx.begin(), gx.end());
    *b = *hi > *lo ? 4 / (*hi - *lo) : 1;
  }
  *a = sy / sw - *b * sx / sw;
}

// Fisher scoring with step halving at fixed guess and lapse rates.
PsychometricFit FitFixedLapse(const PsychometricData& d, const std::vector<double>& gx, Shape s,
                              double guess, double lapse, double a0, double b0) {
  PsychometricFit f;
  double a = a0, b = b0;
  Eval e = Evaluate(d, gx, s, guess, lapse, a, b);
  f.initial_cost = -(e.ll + LogChooseSum(d));
  bool converged = false;
  int it = 0;
  for (; it < 200 && !converged; ++it) {
    const double det = e.i00 * e.i11 - e.i01 * e.i01;
    if (!(det > 0) || !std::isfinite(det)) break;
    double da = (e.i11 * e.g0 - e.i01 * e.g1) / det;
    double db = (e.i00 * e.g1 - e.i01 * e.g0) / det;
    Eval next;
    int halvings = 0;
    for (;; ++halvings) {
      next = Evaluate(d, gx, s, guess, lapse, a + da, b + db);
      if (std::isfinite(next.ll) && next.ll >= e.ll - 1e-12 * std::abs(e.ll)) break;
      if (halvings == 60) break;
      da *= 0.5;
      db *= 0.5;
    }
    if (halvings == 60) {
      converged = std::abs(e.g0) + std::abs(e.g1) < 1e-8;
      break;
    }
    a += da;
    b += db;
    const double change = std::abs(next.ll - e.ll);
    e = next;
    converged = change < 1e-13 * (1 + std::abs(e.ll)) &&
                std::abs(da) + std::abs(db) < 1e-10 * (1 + std::abs(a) + std::abs(b));
  }
  f.iterations = it;
  f.converged = converged;
  f.a = a;
  f.b = b;
  f.log_likelihood = e.ll + LogChooseSum(d);
  f.final_cost = -f.log_likelihood;
  f.deviance = std::max(0.0, 2 * (SaturatedLogLik(d) - e.ll));
  if (const double det = e.i00 * e.i11 - e.i01 * e.i01; det > 0) {
    f.se_a = std::sqrt(e.i11 / det);
    f.se_b = std::sqrt(e.i00 / det);
  } else {
    f.se_a = f.se_b = std::numeric_limits<double>::quiet_NaN();
  }
  f.params.guess = guess;
  f.params.lapse = lapse;
  f.params.slope = b;
  const double g_alpha = b != 0 ? -a / b : 0;
  f.params.threshold = s == Shape::kWeibull ? std::exp(g_alpha) : g_alpha;
  f.usable = converged && b != 0 && std::isfinite(a) && std::isfinite(b) && std::abs(b) < 1e8 &&
             std::isfinite(f.params.threshold);
  f.message =
      f.usable ? "converged"
               : (converged
                      ? "degenerate fit (slope 0 or unbounded: the data may be perfectly separated)"
                      : fmt::format("did not converge in {} iterations", it));
  return f;
}

}  // namespace

bool PsychometricFitOptions::IsValid(std::string* why) const {
  std::string w;
  if (!(guess >= 0 && guess < 1))
    w = "guess rate must be in [0, 1)";
  else if (!lapse_free && !(lapse >= 0 && lapse < 1 - guess))
    w = "lapse rate must be in [0, 1 - guess)";
  else if (lapse_free && !(max_lapse > 0 && max_lapse < 1 - guess))
    w = "max_lapse must be in (0, 1 - guess)";
  if (why) *why = w;
  return w.empty();
}

PsychometricFit FitPsychometric(const PsychometricData& d, const PsychometricFitOptions& o) {
  std::string why;
  HL_REQUIRE(o.IsValid(&why), "psychometric fit: " + why);
  HL_REQUIRE(d.x.size() == d.n.size() && d.x.size() == d.k.size(),
             "psychometric fit: x, n and k must have the same length");
  std::vector<double> gx;
  const auto unusable = [](std::string why_not) {
    PsychometricFit f;
    f.message = std::move(why_not);
    return f;
  };
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    if (d.n[i] < 1 || d.k[i] < 0 || d.k[i] > d.n[i])
      return unusable(fmt::format("bin {} has k = {} of n = {}", i, d.k[i], d.n[i]));
    if (o.shape == Shape::kWeibull && !(d.x[i] > 0)) return unusable("a Weibull needs stimuli > 0");
    gx.push_back(psychophysics::Predictor(o.shape, d.x[i]));
  }
  if (gx.size() < 2 ||
      *std::max_element(gx.begin(), gx.end()) == *std::min_element(gx.begin(), gx.end())) {
    PsychometricFit f;
    f.message = "needs at least two distinct stimulus values";
    return f;
  }
  double a0 = 0, b0 = 0;
  if (!o.lapse_free) {
    StartValues(d, gx, o.shape, o.guess, o.lapse, &a0, &b0);
    return FitFixedLapse(d, gx, o.shape, o.guess, o.lapse, a0, b0);
  }
  // Free lapse: golden-section search of the profile likelihood over [0, max_lapse]. Each
  // profile point starts from the previous fit.
  StartValues(d, gx, o.shape, o.guess, 0, &a0, &b0);
  PsychometricFit best;
  best.log_likelihood = -std::numeric_limits<double>::infinity();
  auto profile = [&](double lam) {
    PsychometricFit f = FitFixedLapse(d, gx, o.shape, o.guess, lam, a0, b0);
    if (f.usable) {
      a0 = f.a;
      b0 = f.b;
      if (f.log_likelihood > best.log_likelihood) best = f;
      return f.log_likelihood;
    }
    return -std::numeric_limits<double>::infinity();
  };
  const double r = (std::sqrt(5.0) - 1) / 2;
  double lo = 0, hi = o.max_lapse;
  double c = hi - r * (hi - lo), dd = lo + r * (hi - lo);
  double fc = profile(c), fd = profile(dd);
  int iters = 0;
  while (hi - lo > 1e-11 && iters < 200) {
    ++iters;
    if (fc >= fd) {
      hi = dd, dd = c, fd = fc;
      c = hi - r * (hi - lo);
      fc = profile(c);
    } else {
      lo = c, c = dd, fc = fd;
      dd = lo + r * (hi - lo);
      fd = profile(dd);
    }
  }
  // The ends of the interval are candidates too (the profile can peak at a bound).
  profile(0);
  profile(o.max_lapse);
  if (!best.usable) best.message = "no lapse rate in [0, max_lapse] gave a usable fit";
  return best;
}

PsychometricBootstrap BootstrapPsychometric(const PsychometricData& d,
                                            const PsychometricFitOptions& o,
                                            const PsychometricFit& fit, int replicates,
                                            std::uint64_t seed, double level,
                                            double jnd_performance,
                                            const std::vector<double>& performances) {
  HL_REQUIRE(fit.usable, "bootstrap: the fit is not usable: " + fit.message);
  HL_REQUIRE(replicates >= 2 && level > 0 && level < 1,
             "bootstrap: needs >= 2 replicates and 0 < level < 1");
  for (const double p : performances)
    HL_REQUIRE(p > o.guess && p < 1, "bootstrap: each performance must be in (guess, 1)");
  PsychometricBootstrap out;
  out.level = level;
  out.jnd = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  Rng rng(seed);
  std::vector<double> thr, slope, jnd;
  std::vector<std::vector<double>> at(performances.size());
  // A replicate whose lapse leaves the performance unreachable counts as infinitely far.
  const auto stimulus_at = [&o](const psychophysics::PsychometricParams& p, double perf) {
    const auto x = psychophysics::StimulusAt(o.shape, p, perf);
    return x ? *x : std::numeric_limits<double>::infinity();
  };
  PsychometricData sim = d;
  for (int r = 0; r < replicates; ++r) {
    for (std::size_t i = 0; i < d.x.size(); ++i) {
      const double p = psychophysics::Psi(o.shape, d.x[i], fit.params);
      int k = 0;
      for (int j = 0; j < d.n[i]; ++j) k += rng.Uniform() < p;
      sim.k[i] = k;
    }
    const PsychometricFit f = FitPsychometric(sim, o);
    if (!f.usable) {
      ++out.failed;
      continue;
    }
    thr.push_back(f.params.threshold);
    slope.push_back(f.params.slope);
    if (jnd_performance > o.guess && jnd_performance < 1)
      jnd.push_back(stimulus_at(f.params, jnd_performance));
    for (std::size_t j = 0; j < performances.size(); ++j)
      at[j].push_back(stimulus_at(f.params, performances[j]));
  }
  out.replicates = static_cast<int>(thr.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.stimulus_at.assign(performances.size(), BootstrapInterval{nan, nan});
  out.threshold = out.slope = {nan, nan};
  if (thr.size() < 2) return out;
  // Percentile interval (type 7 quantiles, as R's quantile()).
  auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const double h = (static_cast<double>(v.size()) - 1) * q;
    const auto lo = static_cast<std::size_t>(std::floor(h));
    const std::size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
  };
  const double tail = (1 - level) / 2;
  out.threshold = {quantile(thr, tail), quantile(thr, 1 - tail)};
  out.slope = {quantile(slope, tail), quantile(slope, 1 - tail)};
  out.jnd = jnd.empty() ? out.jnd : BootstrapInterval{quantile(jnd, tail), quantile(jnd, 1 - tail)};
  for (std::size_t j = 0; j < at.size(); ++j)
    out.stimulus_at[j] = {quantile(at[j], tail), quantile(at[j], 1 - tail)};
  return out;
}

PsychometricData PoolByStimulus(const PsychometricData& d) {
  std::map<double, std::pair<int, int>> bins;
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    auto& b = bins[d.x[i]];
    b.first += d.n[i];
    b.second += d.k[i];
  }
  PsychometricData out;
  for (const auto& [x, nk] : bins) {
    out.x.push_back(x);
    out.n.push_back(nk.first);
    out.k.push_back(nk.second);
  }
  return out;
}

}  // namespace hapticlab::stats
