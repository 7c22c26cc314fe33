#pragma once
// Float sums that vectorise. A plain `for (...) sum += term` is one serial chain
// of adds that the compiler must keep (float addition is not associative), about
// four cycles a term; 16 partial sums are independent chains it turns into
// vector adds. The result differs from the serial sum only by rounding.

#include <cstddef>

namespace flutterscan::imaging {

/// \brief The sum of term(i) for i in [0, n), over 16 partial sums.
template <typename Term>
float lane_sum(std::size_t n, const Term& term) {
  constexpr std::size_t kLanes = 16;
  float lanes[kLanes] = {};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes)
    for (std::size_t k = 0; k < kLanes; ++k) lanes[k] += term(i + k);
  float sum = 0;
  for (; i < n; ++i) sum += term(i);
  for (float lane : lanes) sum += lane;
  return sum;
}

}  // namespace flutterscan::imaging
