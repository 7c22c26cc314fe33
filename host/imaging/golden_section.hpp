#pragma once
// Golden-section search for the minimum of a one-dimensional cost.

#include <cmath>

namespace flutterscan::imaging {

/// \brief The minimum of `cost` (unimodal on [lo, hi]) to within `tolerance`.
template <typename Cost>
double golden_minimum(Cost&& cost, double lo, double hi, double tolerance) {
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  double a = hi - ratio * (hi - lo), b = lo + ratio * (hi - lo);
  double fa = cost(a), fb = cost(b);
  while (hi - lo > tolerance) {
    if (fa < fb) {
      hi = b;
      b = a;
      fb = fa;
      a = hi - ratio * (hi - lo);
      fa = cost(a);
    } else {
      lo = a;
      a = b;
      fa = fb;
      b = lo + ratio * (hi - lo);
      fb = cost(b);
    }
  }
  return (lo + hi) / 2;
}

}  // namespace flutterscan::imaging
