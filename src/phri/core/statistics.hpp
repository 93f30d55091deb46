#pragma once
// Summary statistics of sampled values, one definition for the whole framework (the run summary's
// cycle times, the experiments' error percentiles and medians).
#include <vector>

namespace phri {

/// The p-quantile of `values`, p in [0, 1] (clamped); 0 when empty. Linear interpolation between
/// the closest ranks: with the values sorted, rank r = p (n - 1) and the result is
/// v[floor(r)] + (r - floor(r)) (v[floor(r) + 1] - v[floor(r)]) — numpy.percentile's default
/// ("linear"), so p = 0.5 is the median (the mean of the middle two for an even count).
double percentile(std::vector<double> values, double p);

/// Root mean square of `values`; 0 when empty.
double rms(const std::vector<double>& values);

}  // namespace phri
