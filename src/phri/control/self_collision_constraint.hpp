#pragma once
// Self-collision avoidance of the QP (paper, "Safety Features"): the velocity damper
// (velocity_damper.hpp) on the distance d of each capsule pair, d̈ = J_d qdd + J̇_d qd >= damper,
// active inside the influence distance (paper: d_i 0.03 m, d_s 0.015 m, M 1.8).
#include <phri/control/constraint.hpp>
#include <phri/control/velocity_damper.hpp>
#include <phri/model/collision_model.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {

/// Braking distance ahead of the damper (ours, not the paper's). The damper allows xi (0.08 m/s) at
/// d_i (3 cm) and nothing bounds the approach outside d_i, where a push can carry a link faster than
/// the torque limits stop within d_i - d_s (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 5150 full_body/kinova_torque/1). So the
/// approach speed is also bounded by what `deceleration` stops before d_s:
/// -ḋ <= v(d) = min(sqrt(2 a (d - d_s)), gain / 5 (d - d_s)), as d̈ >= -gain (ḋ + v(d)) (the
/// linear end keeps the lag of a first-order tracker from overshooting d_s where the square root's
/// slope grows without bound); the row enters once the pair approaches faster than half of v(d),
/// where it does not bind yet (slow motion never meets it). A comfort row: where it would make the
/// QP infeasible with the torque limits, the QP solves again without it (WholeBodyQp::update).
struct CollisionBrakingSettings {
  double deceleration = 3.0;  ///< [m/s^2] a; 0: off (the paper's damper alone)
  double gain = 50.0;         ///< [1/s]
};

/// The braking row's lowest d̈ at distance d approaching at ḋ (-inf where it is left out).
inline double collision_braking_bound(double d, double d_dot, double safety_distance, const CollisionBrakingSettings& b) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(b.deceleration > 0.0)) return -kInf;
  const double x = std::max(d - safety_distance, 0.0);
  const double allowed = std::min(std::sqrt(2.0 * b.deceleration * x), 0.2 * b.gain * x);
  return -d_dot > 0.5 * allowed ? -b.gain * (d_dot + allowed) : -kInf;
}

/// Whether collision_braking_bound(d, d_dot, ...) is -inf (the braking row left out), to the same
/// answer without its square root unless the squares lie within rounding of the boundary: the broad
/// phase asks it of every pair each cycle. Approaching at s = -d_dot: in iff s > min(sqrt(2 a x),
/// 0.2 gain x) / 2, i.e. s > 0.1 gain x or (2 s)^2 > 2 a x.
inline bool collision_braking_left_out(double d, double d_dot, double safety_distance, const CollisionBrakingSettings& b) {
  if (!(b.deceleration > 0.0)) return true;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!std::isfinite(b.deceleration) || !std::isfinite(b.gain)) {
    return collision_braking_bound(d, d_dot, safety_distance, b) == -kInf;
  }
  const double x = std::max(d - safety_distance, 0.0);
  const double approach = -d_dot;
  if (approach > 0.5 * (0.2 * b.gain * x)) return false;  // beyond the linear end, so beyond the minimum
  if (!(approach > 0.0)) return true;
  const double squared = 2.0 * b.deceleration * x;  // the root's argument, as collision_braking_bound forms it
  const double twice = 2.0 * approach;
  constexpr double kMargin = 1e-12, kTiny = 1e-150, kHuge = 1e150;  // far above rounding; no under/overflow
  if (squared > kTiny && twice < kHuge) {
    if (twice * twice < squared * (1.0 - kMargin)) return true;
    if (twice * twice > squared * (1.0 + kMargin)) return false;
  }
  return !(approach > 0.5 * std::sqrt(squared));
}

class SelfCollisionConstraint final : public Constraint {
public:
  SelfCollisionConstraint(const Model& model, const CollisionModel& collision, const VelocityDamperSettings& damper,
                          const CollisionBrakingSettings& braking = {0.0, 50.0})
      : collision_(&collision),
        data_(model, collision),
        damper_(damper),
        influence_distance_(damper.influence_distance),
        safety_distance_(damper.safety_distance),
        braking_(braking),
        damper_lower_(Eigen::VectorXd::Zero(collision.num_pairs())) {}

  std::string_view type() const override { return "self_collision"; }
  int num_rows() const override { return collision_->num_pairs(); }
  void begin_cycle() override { relaxed_ = false; }
  /// The rows, without the braking rows once relaxed in this cycle.
  void fill_rows(const ConstraintContext& context, Eigen::Ref<Eigen::MatrixXd> a, Eigen::Ref<Eigen::VectorXd> l,
                 Eigen::Ref<Eigen::VectorXd> u) override {
    rows(context.model, context.data, a, l, u);
    if (relaxed_) l = damper_lower_;
  }
  /// Drops the braking rows for this cycle where they bind (the damper alone rather than the fallback).
  bool relax() override {
    if (relaxed_ || !braking_binds_) return false;
    relaxed_ = true;
    return true;
  }

  /// Distances at the current state (data: after the model terms), then one row per pair. A pair
  /// beyond the influence distance whose braking row is left out bounds nothing (-inf <= row):
  /// its row is zero and its Jacobian is not computed; a pair whose bounding spheres already show
  /// that (distance bound beyond the influence distance, approach too slow for the braking row
  /// there: the bound grows with distance) gets no closest points either, and data().distance
  /// holds that lower bound for it (the broad phase; the QP is the same).
  template <class Rows, class Bound>
  void rows(const Model& model, const Data& data, Rows&& a, Bound&& l, Bound&& u) {
    compute_collision_bounds(model, data, *collision_, data_);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    braking_binds_ = false;
    for (int p = 0; p < num_rows(); ++p) {
      u[p] = kInf;
      const double bound = data_.distance_lower_bound[p];
      const bool far = bound >= influence_distance_ &&
                       collision_braking_left_out(bound, -data_.approach_speed_bound[p], safety_distance_, braking_);
      if (far) {
        data_.distance[p] = bound;
        data_.velocity[p] = 0.0;
      } else {
        compute_collision_pair_distance_rate(model, data, *collision_, p, data_);
      }
      const double d = data_.distance[p];
      const double d_dot = data_.velocity[p];
      if (far || (d >= influence_distance_ && collision_braking_left_out(d, d_dot, safety_distance_, braking_))) {
        a.row(p).setZero();
        data_.jacobian.row(p).setZero();
        data_.jdot_qdot[p] = 0.0;
        l[p] = damper_lower_[p] = -kInf;
        continue;
      }
      compute_collision_pair_derivatives(model, data, *collision_, p, data_);
      a.row(p) = data_.jacobian.row(p);
      damper_lower_[p] = (d < influence_distance_ ? damper_.min_acceleration(d, d_dot) : -kInf) - data_.jdot_qdot[p];
      const double braking = collision_braking_bound(d, d_dot, safety_distance_, braking_) - data_.jdot_qdot[p];
      braking_binds_ = braking_binds_ || braking > damper_lower_[p];
      l[p] = std::max(damper_lower_[p], braking);
    }
  }
  /// Whether a braking row is tighter than the damper on some pair (last rows()).
  bool braking_binds() const { return braking_binds_; }
  /// The rows' lower bounds of the paper's damper alone (last rows()).
  const Eigen::VectorXd& damper_lower() const { return damper_lower_; }
  const CollisionData& data() const { return data_; }

private:
  const CollisionModel* collision_;
  CollisionData data_;
  VelocityDamper damper_;
  double influence_distance_, safety_distance_;
  CollisionBrakingSettings braking_;
  Eigen::VectorXd damper_lower_;
  bool braking_binds_ = false;
  bool relaxed_ = false;  // the braking rows dropped for this cycle
};

}  // namespace phri
