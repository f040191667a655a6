#pragma once
/// @file Kruskal-Wallis with tie correction, Dunn's test with Bonferroni adjustment, and the
/// A/B/C grouping of materials against the real-real limits (dissertation ch. IV.5.2).
///
/// Values are rounded to 9 decimals before ranking, so cell means that are equal in exact
/// arithmetic tie as they should (averaging leaves 1e-15 differences that would otherwise
/// break ties; the R fixtures do the same).

#include <string>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct DunnPair {
  std::string a, b;  ///< groups, a before b in level order
  int n_a = 0, n_b = 0;
  double z = 0;             ///< (mean rank b − mean rank a) / SE, with the tie-corrected variance
  double p = 0, p_adj = 0;  ///< two-sided; Bonferroni over all k(k−1)/2 pairs, capped at 1
};

struct KruskalResult {
  std::string factor;
  std::vector<std::string> groups;
  int N = 0;
  double H = 0, df = 0, p = 0;
  double H_uncorrected = 0, tie_correction = 1;
  std::vector<DunnPair> dunn;
};

/// @throws InputError for fewer than 2 groups or all values tied
KruskalResult KruskalWallis(const LongTable& data, const std::string& factor);

/// Letter of one material against the limits (Fig. 4.5): "A" differs from the lower limit
/// but not the upper, "B" from the upper but not the lower, "C" from neither, "D" from both.
struct LimitGroup {
  std::string material;
  std::string letter;
  double p_adj_vs_upper = 1, p_adj_vs_lower = 1;
};
/// Runs Kruskal-Wallis + Dunn-Bonferroni over all groups (materials and the two limits) and
/// classifies each material at level `alpha`.
std::vector<LimitGroup> GroupAgainstLimits(const LongTable& data, const std::string& factor,
                                           const std::string& upper, const std::string& lower,
                                           double alpha = 0.05);

}  // namespace hapticlab::stats
