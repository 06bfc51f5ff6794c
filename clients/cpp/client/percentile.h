#pragma once
/// @file percentile.h
/// Percentiles of measured latencies, for benchmarks and load tests.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace rmap::client {

/// The value of rank floor(q · n) among `values` (0 ≤ q ≤ 1; q = 1 gives the
/// maximum); 0 for no values.
inline double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace rmap::client
