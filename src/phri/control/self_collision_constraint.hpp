#pragma once
// Self-collision avoidance of the QP (paper, "Safety Features"): the velocity damper
// (velocity_damper.hpp) on the distance d of each capsule pair, d̈ = J_d qdd + J̇_d qd >= damper,
// active inside the influence distance (paper: d_i 0.03 m, d_s 0.015 m, M 1.8).
#include <phri/control/velocity_damper.hpp>
#include <phri/model/collision_model.hpp>

#include <limits>

namespace phri {

class SelfCollisionConstraint {
public:
  SelfCollisionConstraint(const Model& model, const CollisionModel& collision, const VelocityDamperSettings& damper)
      : collision_(&collision), data_(model, collision), damper_(damper), influence_distance_(damper.influence_distance) {}

  int num_rows() const { return collision_->num_pairs(); }

  /// Distances at the current state (data: after the model terms), then one row per pair.
  template <class Rows, class Bound>
  void rows(const Model& model, const Data& data, Rows&& a, Bound&& l, Bound&& u) {
    compute_collision_distances(model, data, *collision_, data_, true);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    for (int p = 0; p < num_rows(); ++p) {
      a.row(p) = data_.jacobian.row(p);
      u[p] = kInf;
      const double d = data_.distance[p];
      l[p] = d < influence_distance_ ? damper_.min_acceleration(d, data_.velocity[p]) - data_.jdot_qdot[p] : -kInf;
    }
  }
  const CollisionData& data() const { return data_; }

private:
  const CollisionModel* collision_;
  CollisionData data_;
  VelocityDamper damper_;
  double influence_distance_;
};

}  // namespace phri
