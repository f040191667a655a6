// Multi-site analysis: the LMM with a site term, the site SD's parametric bootstrap, per-site
// effects, and the replication summary (small telescopes).
#include "hapticlab/stats/multisite.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {

namespace {

// Weights of one method level's marginal mean on the sum-to-zero coefficients method1..:
// level j < K-1 is β0 + β_{j+1}, the last level β0 - Σ β (the intercept cancels in a
// difference and is left out).
std::vector<std::pair<std::string, double>> LevelWeights(const std::vector<std::string>& levels,
                                                         const std::string& level, double sign) {
  const auto k =
      static_cast<std::size_t>(std::find(levels.begin(), levels.end(), level) - levels.begin());
  std::vector<std::pair<std::string, double>> w;
  if (k + 1 < levels.size()) {
    w.emplace_back("method" + std::to_string(k + 1), sign);
  } else {
    for (std::size_t j = 0; j + 1 < levels.size(); ++j)
      w.emplace_back("method" + std::to_string(j + 1), -sign);
  }
  return w;
}

double Percentile(std::vector<double> v, double p) {  // R's type 7
  std::sort(v.begin(), v.end());
  const double h = (static_cast<double>(v.size()) - 1) * p;
  const auto i = static_cast<std::size_t>(std::floor(h));
  return i + 1 < v.size() ? v[i] + (h - static_cast<double>(i)) * (v[i + 1] - v[i]) : v[i];
}

const LmmRandomTerm* Term(const LmmResult& m, const std::string& group) {
  for (const auto& t : m.random)
    if (t.group == group) return &t;
  return nullptr;
}

// Per-site participant differences (last - first), means per site and method.
void SiteSummaries(const LongTable& data, MultiSiteFit& fit) {
  const LongTable avg = data.Average({"site", "participant", "method"});
  const auto& site = avg.keys[avg.Key("site")];
  const auto& part = avg.keys[avg.Key("participant")];
  const auto& method = avg.keys[avg.Key("method")];
  std::map<std::string, std::map<std::string, std::map<std::string, double>>> by;  // s, p, m
  for (std::size_t r = 0; r < avg.rows(); ++r) by[site[r]][part[r]][method[r]] = avg.y[r];
  std::map<std::string, std::vector<double>> pooled;
  double ss_within = 0;
  int n_total = 0;
  for (const auto& [s, parts] : by) {
    std::map<std::string, std::vector<double>> means;
    std::vector<double> diffs;
    for (const auto& [p, ms] : parts) {
      for (const auto& [m, v] : ms) {
        means[m].push_back(v);
        pooled[m].push_back(v);
      }
      if (ms.count(fit.first) && ms.count(fit.last))
        diffs.push_back(ms.at(fit.last) - ms.at(fit.first));
    }
    for (const auto& [m, v] : means) {
      double sum = 0;
      for (double x : v) sum += x;
      fit.site_means[s][m] = sum / static_cast<double>(v.size());
    }
    SiteEffect e{.site = s, .participants = static_cast<int>(diffs.size())};
    double sum = 0, ss = 0;
    for (double d : diffs) sum += d;
    e.estimate = diffs.empty() ? NAN : sum / static_cast<double>(diffs.size());
    for (double d : diffs) ss += (d - e.estimate) * (d - e.estimate);
    const double n = static_cast<double>(diffs.size());
    const double half = diffs.size() > 1 ? Qt(0.975, n - 1) * std::sqrt(ss / (n - 1) / n) : NAN;
    e.low = e.estimate - half;
    e.high = e.estimate + half;
    ss_within += ss;
    n_total += static_cast<int>(diffs.size());
    fit.sites.push_back(e);
  }
  for (const auto& [m, v] : pooled) {
    double sum = 0;
    for (double x : v) sum += x;
    fit.pooled_means[m] = sum / static_cast<double>(v.size());
  }
  fit.participants = static_cast<int>(avg.Levels("participant").size());
  const int df = n_total - static_cast<int>(by.size());
  fit.sd_difference = df > 0 ? std::sqrt(ss_within / df) : NAN;
}

// The site SD's parametric bootstrap: responses drawn from the fitted random effects and
// residual (REML variance estimates do not depend on the fixed effects, so they are left
// out), refitted with the same formula; the 2.5 % and 97.5 % percentiles of the refits'
// site SDs (lme4's confint(method = "boot", type = "perc")).
void BootstrapSiteSd(const LongTable& data, const std::vector<std::string>& levels,
                     const MultiSiteOptions& o, MultiSiteFit& fit) {
  const LmmRandomTerm* pt = Term(fit.model, "site:participant");
  if (!pt || o.bootstrap <= 0) return;
  const auto q = static_cast<Eigen::Index>(pt->sd.size());
  Eigen::MatrixXd cov(q, q);
  for (Eigen::Index i = 0; i < q; ++i)
    for (Eigen::Index j = 0; j < q; ++j) {
      const double c = pt->corr[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
      cov(i, j) = pt->sd[static_cast<std::size_t>(i)] * pt->sd[static_cast<std::size_t>(j)] *
                  (std::isfinite(c) ? c : 0.0);
    }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  const Eigen::MatrixXd root =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  const auto& site = data.keys[data.Key("site")];
  const auto& part = data.keys[data.Key("participant")];
  const auto& method = data.keys[data.Key("method")];
  Rng rng(o.seed);
  std::vector<double> sds;
  LongTable sim = data;
  for (int b = 0; b < o.bootstrap; ++b) {
    std::map<std::string, double> a;
    std::map<std::string, Eigen::VectorXd> u;
    for (const auto& s : data.Levels("site")) a[s] = rng.Normal(0, fit.site_sd);
    for (std::size_t r = 0; r < data.rows(); ++r) {
      const std::string key = site[r] + ":" + part[r];
      if (!u.count(key)) {
        Eigen::VectorXd z(q);
        for (Eigen::Index i = 0; i < q; ++i) z[i] = rng.Normal();
        u[key] = root * z;
      }
      // Z row of (1 + method | ...): 1, then the level's sum-to-zero code.
      const auto k = static_cast<Eigen::Index>(std::find(levels.begin(), levels.end(), method[r]) -
                                               levels.begin());
      double zb = u[key][0];
      for (Eigen::Index j = 1; j < q; ++j)
        zb += u[key][j] * (k + 1 == static_cast<Eigen::Index>(levels.size()) ? -1.0
                           : k == j - 1                                      ? 1.0
                                                                             : 0.0);
      sim.y[r] = a[site[r]] + zb + rng.Normal(0, fit.model.sigma);
    }
    try {
      const LmmResult m = FitLmm(sim, fit.formula);
      if (const auto* st = Term(m, "site"); st && m.converged) sds.push_back(st->sd[0]);
    } catch (const InputError&) {
    }
  }
  fit.bootstrap_fits = static_cast<int>(sds.size());
  if (sds.size() < 2) return;
  fit.site_sd_low = Percentile(sds, 0.025);
  fit.site_sd_high = Percentile(sds, 0.975);
}

}  // namespace

MultiSiteFit FitMultiSite(const LongTable& data, const std::vector<std::string>& methods,
                          const MultiSiteOptions& o) {
  MultiSiteFit fit;
  const auto levels = data.Levels("method");
  std::vector<std::string> order;
  for (const auto& m : methods)
    if (std::count(levels.begin(), levels.end(), m)) order.push_back(m);
  if (data.Levels("site").size() < 2 || order.size() < 2)
    throw InputError(data.source, 0, "site",
                     "a multi-site analysis needs two or more sites and two or more methods");
  fit.first = order.front();
  fit.last = order.back();
  fit.formula = data.y_name +
                (data.Levels("material").size() > 1 ? " ~ method * material" : " ~ method") +
                " + (1 | site) + (1 + method | site:participant)";
  LmmContrast con{fit.last + " - " + fit.first, LevelWeights(levels, fit.last, 1.0)};
  for (const auto& w : LevelWeights(levels, fit.first, -1.0)) con.weights.push_back(w);
  fit.model = FitLmm(data, fit.formula, {.contrasts = {con}});
  fit.pooled = fit.model.contrasts.at(0);
  const double half = Qt(0.975, fit.pooled.df) * fit.pooled.se;
  fit.pooled_low = fit.pooled.estimate - half;
  fit.pooled_high = fit.pooled.estimate + half;
  if (const auto* st = Term(fit.model, "site")) fit.site_sd = st->sd[0];
  SiteSummaries(data, fit);
  BootstrapSiteSd(data, levels, o, fit);
  return fit;
}

std::optional<OriginalEffect> ShinOriginalEffect(const std::string& protocol_name,
                                                 const std::string& criterion,
                                                 const std::string& first,
                                                 const std::string& last) {
  // Ch. V.3 (15 participants): method means over the ten materials, Tables 5.4 (roughness)
  // and 5.5 (overall); the same values are the observer's calibration targets
  // (studies/shin2019/calibration.toml).
  struct Row {
    const char* criterion;
    double lpc, ff, hybrid;
    const char* table;
  };
  static constexpr Row kCh5[] = {{"roughness", 59.509, 62.405, 66.533, "Table 5.4"},
                                 {"overall", 59.038, 61.310, 65.295, "Table 5.5"}};
  if (protocol_name.find("ch5") == std::string::npos ||
      protocol_name.find("hybrid") == std::string::npos)
    return std::nullopt;
  for (const auto& r : kCh5) {
    if (criterion != r.criterion) continue;
    const auto mean = [&](const std::string& m) -> std::optional<double> {
      if (m == "LPC") return r.lpc;
      if (m == "FF") return r.ff;
      if (m == "Hybrid") return r.hybrid;
      return std::nullopt;
    };
    const auto a = mean(first), b = mean(last);
    if (!a || !b) return std::nullopt;
    return OriginalEffect{*b - *a, 15,
                          fmt::format("Shin 2019, {} (means of the ten materials)", r.table)};
  }
  return std::nullopt;
}

double PairedTPower(double dz, int n) {
  const double df = n - 1, delta = dz * std::sqrt(static_cast<double>(n));
  const double c = Qt(0.975, df);
  const boost::math::chi_squared chi(df);
  const auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  // Simpson's rule over v ~ chi-square(df): P(|T| > c | v) with T = (Z + delta) / sqrt(v/df).
  const double hi = df + 14 * std::sqrt(2 * df) + 30;
  constexpr int kSteps = 1000;
  const double h = hi / kSteps;
  double sum = 0;
  for (int i = 0; i <= kSteps; ++i) {
    const double v = i * h, s = c * std::sqrt(v / df);
    const double f = v > 0 ? boost::math::pdf(chi, v) : 0.0;
    const double w = i == 0 || i == kSteps ? 1 : (i % 2 ? 4 : 2);
    sum += w * f * (phi(delta - s) + phi(-s - delta));
  }
  return sum * h / 3;
}

double SmallTelescopeD33(int n) {
  double lo = 0, hi = 5;
  for (int i = 0; i < 34; ++i) {  // to 3e-10
    const double mid = 0.5 * (lo + hi);
    (PairedTPower(mid, n) < 1.0 / 3 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::string ReplicationStatement(const MultiSiteFit& f, const OriginalEffect& orig) {
  const double sign = orig.effect < 0 ? -1 : 1;
  const double est = sign * f.pooled.estimate;
  const double lower95 = est - Qt(0.975, f.pooled.df) * f.pooled.se;
  const double upper90 = est + Qt(0.95, f.pooled.df) * f.pooled.se;  // one-sided 95 %
  const double dz33 = SmallTelescopeD33(orig.participants);
  const double d33 = dz33 * f.sd_difference;
  std::string out = fmt::format(
      "Pooled method effect {} - {}: {:.2f} points (95 % CI [{:.2f}, {:.2f}], Satterthwaite df "
      "{:.1f}) over {} sites and {} participants; the original study: {:.2f} points ({}, n = "
      "{}), {} the pooled 95 % CI. ",
      f.last, f.first, f.pooled.estimate, f.pooled_low, f.pooled_high, f.pooled.df, f.sites.size(),
      f.participants, orig.effect, orig.source, orig.participants,
      orig.effect >= f.pooled_low && orig.effect <= f.pooled_high ? "inside" : "outside");
  if (lower95 > 0)
    return out + "Replicated: the pooled effect is significant in the original's direction.\n";
  if (upper90 < d33)
    return out + fmt::format(
                     "Small-telescopes failure (Simonsohn 2015): the pooled effect is "
                     "significantly smaller (one-sided 95 % bound {:.2f}) than d33 = {:.2f} "
                     "points, the effect the original's {} participants had 33 % power to "
                     "detect (dz {:.3f} x the SD {:.2f} of this replication's participant "
                     "differences): the original could not have detected an effect this "
                     "small.\n",
                     sign * upper90, sign * d33, orig.participants, dz33, f.sd_difference);
  return out + fmt::format(
                   "Inconclusive: the pooled effect is neither significant nor significantly "
                   "smaller than d33 = {:.2f} points (dz {:.3f} for the original's {} "
                   "participants x the SD {:.2f} of this replication's participant "
                   "differences); more sites or participants are needed (`study power "
                   "--sites`).\n",
                   sign * d33, dz33, orig.participants, f.sd_difference);
}

}  // namespace hapticlab::stats
