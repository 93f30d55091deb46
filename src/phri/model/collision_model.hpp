#pragma once
// Self-collision geometry: capsules fixed to links (from a collision YAML such as
// robots/kinova_gen3/collision.yaml), the pairs to watch, and their distances with the
// derivatives the controller's velocity damper needs (distance Jacobian and J̇q̇).
//
//   capsules:
//     - {link: forearm_link, p0: [0, 0, 0], p1: [0, -0.2, 0], radius: 0.04}   # link frame, metres
//   pairs:
//     - [base_link, forearm_link]
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

#include <string>
#include <vector>

namespace phri {

struct Capsule {
  std::string link;
  int body = -1;  ///< body the capsule moves with (-1: the base)
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();  ///< segment end points in the body frame
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

struct CapsulePair {
  int first = 0;   ///< index into capsules()
  int second = 0;
};

class CollisionModel {
public:
  /// Throws ConfigError naming the file and the key path (e.g. "capsules[2].radius").
  static CollisionModel from_yaml_file(const std::string& path, const Model& model);
  static CollisionModel from_yaml_string(const std::string& yaml, const Model& model,
                                         const std::string& source_name = "<collision yaml>");

  const std::vector<Capsule>& capsules() const { return capsules_; }
  const std::vector<CapsulePair>& pairs() const { return pairs_; }
  int num_pairs() const { return static_cast<int>(pairs_.size()); }

private:
  std::vector<Capsule> capsules_;
  std::vector<CapsulePair> pairs_;
};

/// Per-pair results, sized once from the collision model.
struct CollisionData {
  explicit CollisionData(const Model& model, const CollisionModel& collision);
  Eigen::VectorXd distance;        ///< surface distance (negative when interpenetrating), m
  Eigen::Matrix3Xd point_first;    ///< closest point on the first capsule's axis, world
  Eigen::Matrix3Xd point_second;
  Eigen::Matrix3Xd normal;         ///< unit, from the second capsule toward the first
  Eigen::MatrixXd jacobian;        ///< pairs x nv: d(distance)/dt = jacobian * qd
  Eigen::VectorXd jdot_qdot;       ///< d2(distance)/dt2 = jacobian * qdd + jdot_qdot
  Eigen::VectorXd velocity;        ///< d(distance)/dt
  Eigen::VectorXd s, t;            ///< where the closest points are along each axis, in [0, 1]
  Eigen::MatrixXd scratch_first;   ///< 3 x nv point Jacobians (workspace)
  Eigen::MatrixXd scratch_second;
  // compute_collision_bounds: per capsule its axis's midpoint (world) and the fastest speed of a
  // point of its axis; per pair a lower bound on the distance and an upper bound on -d(distance)/dt.
  Eigen::Matrix3Xd capsule_center;
  Eigen::VectorXd capsule_speed;
  Eigen::VectorXd capsule_angular_speed;  ///< |omega| of the capsule's body (workspace)
  Eigen::VectorXd distance_lower_bound;
  Eigen::VectorXd approach_speed_bound;
  // Set at construction from the capsules' shapes: per capsule the axis's midpoint in its body's
  // frame and half its length; per pair the two bounding spheres' radii summed.
  Eigen::Matrix3Xd capsule_midpoint;
  Eigen::VectorXd capsule_half_length;
  Eigen::VectorXd pair_reach;
};

/// Distances of every pair from the body placements in `data` (after forward_kinematics).
/// With derivatives (requires velocities and drift accelerations, e.g. compute_all_terms):
/// the distance Jacobian, its J̇q̇ and the distance velocity.
void compute_collision_distances(const Model& model, const Data& data, const CollisionModel& collision,
                                 CollisionData& out, bool with_derivatives);
/// Distances and their rates of every pair (requires velocities), without the Jacobians: the
/// broad phase of a constraint that needs the Jacobian of the pairs near their limit only.
void compute_collision_distance_rates(const Model& model, const Data& data, const CollisionModel& collision,
                                      CollisionData& out);
/// Bounds of every pair from bounding spheres, without the segments' closest points: distance >=
/// |c_a - c_b| - (h_a + r_a) - (h_b + r_b) (c: the axis's midpoint, h: half its length) and
/// -d(distance)/dt <= the two axes' fastest point speeds |v(c)| + |omega| h (requires velocities).
/// A pair whose bounds show it cannot matter to a constraint needs no closest points.
void compute_collision_bounds(const Model& model, const Data& data, const CollisionModel& collision, CollisionData& out);
/// Distance, closest points, normal and rate of pair k (requires velocities).
void compute_collision_pair_distance_rate(const Model& model, const Data& data, const CollisionModel& collision, int k,
                                          CollisionData& out);
/// The distance Jacobian and J̇q̇ of pair k (requires drift accelerations), after
/// compute_collision_distance_rates (or compute_collision_distances) of the same state.
void compute_collision_pair_derivatives(const Model& model, const Data& data, const CollisionModel& collision, int k,
                                        CollisionData& out);

}  // namespace phri
