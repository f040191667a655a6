#pragma once
/// @file Shapiro-Wilk normality test, written here (no maintained C++ library offers it):
/// Royston's algorithm AS R94 [Royston 1995, Applied Statistics 44(4):547-551,
/// doi:10.2307/2986146], the one R's shapiro.test uses, for 3 <= n <= 5000.

#include <vector>

namespace hapticlab::stats {

struct ShapiroResult {
  int n = 0;
  double W = 0;
  double p = 0;
};

/// @throws InputError (field "values") for n < 3, n > 5000, non-finite values or zero range.
ShapiroResult ShapiroWilk(std::vector<double> x);

}  // namespace hapticlab::stats
