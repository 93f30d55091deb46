#pragma once
// Closest points between two segments, the core of capsule-capsule distances (a capsule is the
// set of points within a radius of a segment, so distance = |closest points| - r_a - r_b).
#include <Eigen/Core>

namespace phri {

struct SegmentClosestPoints {
  Eigen::Vector3d on_first = Eigen::Vector3d::Zero();   ///< a0 + s (a1 - a0)
  Eigen::Vector3d on_second = Eigen::Vector3d::Zero();  ///< b0 + t (b1 - b0)
  double s = 0.0;
  double t = 0.0;
  double distance() const { return (on_first - on_second).norm(); }
};

/// Closest points of segments [a0, a1] and [b0, b1]. Degenerate segments (points) and parallel
/// segments are handled: for parallel overlapping segments one of the closest pairs is returned.
SegmentClosestPoints closest_points_between_segments(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                                     const Eigen::Vector3d& b0, const Eigen::Vector3d& b1);

}  // namespace phri
