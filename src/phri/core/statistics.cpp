#include <phri/core/statistics.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace phri {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const double rank = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(rank));
  // Partial ordering is enough (O(n)): v[lo] in place, the larger values after it.
  const auto lo_it = values.begin() + static_cast<std::ptrdiff_t>(lo);
  std::nth_element(values.begin(), lo_it, values.end());
  const double low = *lo_it;
  if (lo + 1 >= values.size()) return low;
  const double high = *std::min_element(lo_it + 1, values.end());
  return low + (rank - static_cast<double>(lo)) * (high - low);
}

double rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace phri
