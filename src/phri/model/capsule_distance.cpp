#include <phri/model/capsule_distance.hpp>

#include <algorithm>

namespace phri {
namespace {
double clamp01(double x) { return std::clamp(x, 0.0, 1.0); }
}  // namespace

// Minimises |a0 + s u - b0 - t v|^2 over the unit square: the unconstrained optimum of the
// 2x2 normal equations, then the edges, as the convex objective's minimum lies on the boundary
// whenever the interior optimum is outside the square.
SegmentClosestPoints closest_points_between_segments(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                                     const Eigen::Vector3d& b0, const Eigen::Vector3d& b1) {
  constexpr double kTiny = 1e-24;  // squared lengths below this are points
  const Eigen::Vector3d u = a1 - a0;
  const Eigen::Vector3d v = b1 - b0;
  const Eigen::Vector3d w = a0 - b0;
  const double uu = u.squaredNorm();
  const double vv = v.squaredNorm();
  const double uv = u.dot(v);
  const double uw = u.dot(w);
  const double vw = v.dot(w);
  double s = 0.0;
  double t = 0.0;
  if (uu <= kTiny && vv <= kTiny) {
    // two points
  } else if (uu <= kTiny) {
    t = clamp01(vw / vv);
  } else if (vv <= kTiny) {
    s = clamp01(-uw / uu);
  } else {
    const double denominator = uu * vv - uv * uv;  // >= 0, zero when parallel
    // Parallel: any s gives a closest pair for the right t; start from s = 0.
    s = denominator > 1e-14 * uu * vv ? clamp01((uv * vw - vv * uw) / denominator) : 0.0;
    t = (uv * s + vw) / vv;
    // t outside [0, 1]: clamp it and recompute the best s for that end of the second segment.
    if (t < 0.0) {
      t = 0.0;
      s = clamp01(-uw / uu);
    } else if (t > 1.0) {
      t = 1.0;
      s = clamp01((uv - uw) / uu);
    }
  }
  SegmentClosestPoints out;
  out.s = s;
  out.t = t;
  out.on_first = a0 + s * u;
  out.on_second = b0 + t * v;
  return out;
}

}  // namespace phri
