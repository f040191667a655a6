#pragma once
/// @file Within-subject confidence intervals of cell means: Cousineau's (2005) normalisation
/// with Morey's (2008) correction, as Rmisc::summarySEwithin computes them on subject x cell
/// means and afex_plot(error = "within") draws them. They show the precision of the
/// differences a within-subject test compares, where between-subject CIs (participant
/// means' spread) would overlap for a pair the test finds significant.

#include <string>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct WithinCi {
  std::vector<std::string> cell;  ///< the levels of `factors`, in their order
  double mean = 0;                ///< mean of the subjects' cell means
  double half_width = 0;          ///< NaN with fewer than 2 subjects
  int n = 0;                      ///< subjects
};

/// The cells are the full crossing of the levels of `factors` (sorted levels, last factor
/// fastest); other columns are averaged within each subject x cell. Subjects lacking a cell
/// are left out (as afex_plot). With J cells and n subjects: y' = y − subject mean + grand
/// mean, half-width = t(1 − (1 − level)/2, n − 1) sd(y'_cell) / sqrt(n) sqrt(J / (J − 1)).
/// @throws InputError when `factors` is empty or a column is missing
std::vector<WithinCi> WithinSubjectCi(const LongTable& data, const std::string& subject,
                                      const std::vector<std::string>& factors, double level = 0.95);

}  // namespace hapticlab::stats
