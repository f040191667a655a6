#pragma once
/// @file Multi-site analysis of realism scores (docs/replication.md, "Combining sites"): the
/// LMM `score ~ method * material + (1 | site) + (1 + method | site:participant)`, the site
/// SD with a parametric-bootstrap interval, per-site means and method effects (a forest plot),
/// and a replication summary against the original study (small telescopes, Simonsohn 2015).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct MultiSiteOptions {
  /// Parametric-bootstrap refits of the site SD's interval (lme4's confint(method = "boot"),
  /// percentile interval).
  int bootstrap = 200;
  std::uint64_t seed = 20150501;  ///< of the bootstrap draws (the report is reproducible)
};

/// The method effect (last method - first method, in the protocol's order) at one site:
/// the mean of its participants' differences (each averaged over materials and repetitions)
/// with a 95 % t interval over participants.
struct SiteEffect {
  std::string site;
  int participants = 0;
  double estimate = 0, low = 0, high = 0;
};

struct MultiSiteFit {
  std::string formula;
  std::string first, last;  ///< the methods of the effect (last - first)
  LmmResult model;
  /// The pooled method effect: the LMM contrast of the two methods' marginal means (every
  /// material weighted equally, as Tables 5.4/5.5 average them), Satterthwaite df and 95 % CI.
  LmmCoefficient pooled;
  double pooled_low = 0, pooled_high = 0;
  double site_sd = 0;                        ///< the fitted SD of the (1 | site) intercepts
  double site_sd_low = 0, site_sd_high = 0;  ///< 2.5 % and 97.5 % bootstrap percentiles
  int bootstrap_fits = 0;                    ///< refits that converged and were used
  std::vector<SiteEffect> sites;             ///< sorted by site code
  /// Mean score per site and method (participants' means), and pooled over sites.
  std::map<std::string, std::map<std::string, double>> site_means;
  std::map<std::string, double> pooled_means;
  /// SD of the participants' differences (last - first), pooled over sites (for d33).
  double sd_difference = 0;
  int participants = 0;
};

/// Fits the multi-site model to one criterion's main-phase ratings (`data` has key columns
/// site, participant, method, material; response score). `methods`: the protocol's order.
/// @throws InputError (data.source) with fewer than two sites or two methods
MultiSiteFit FitMultiSite(const LongTable& data, const std::vector<std::string>& methods,
                          const MultiSiteOptions& options = {});

/// The original study's method effect for a replication summary.
struct OriginalEffect {
  double effect = 0;  ///< last - first method [rating points]
  int participants = 0;
  std::string source;  ///< e.g. "Shin 2019, Table 5.4 (means of the ten materials)"
};

/// The dissertation's value for a shin2019 protocol (by protocol name), criterion and pair of
/// methods; none for any other.
std::optional<OriginalEffect> ShinOriginalEffect(const std::string& protocol_name,
                                                 const std::string& criterion,
                                                 const std::string& first, const std::string& last);

/// Power of a two-sided paired t test at level 0.05 for standardized effect dz and n pairs
/// (the noncentral t by quadrature over the chi-square of the SD).
double PairedTPower(double dz, int n);
/// Simonsohn's (2015) d33: the dz that `n` pairs detect with power 1/3.
double SmallTelescopeD33(int n);

/// The replication summary's sentence: the pooled effect against the original (95 % CI
/// contains it or not) and the small-telescopes verdict (docs/replication.md).
std::string ReplicationStatement(const MultiSiteFit& fit, const OriginalEffect& original);

}  // namespace hapticlab::stats
