// The upper median of a sample (the element at index size / 2 after sorting; no averaging of the two
// middle ones): robust levels of residual energies and parallaxes. 0 for an empty sample.
#pragma once
#include <algorithm>
#include <cstddef>
#include <vector>

namespace rsvio {

inline double upperMedian(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace rsvio
