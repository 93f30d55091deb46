#pragma once
// The way back after a hand has carried the arm (not in the paper).
//
// Full-body compliance lets a hand carry the arm anywhere (gamma 1 on both tasks). On release, the
// end-effector spring pulls straight toward its target in Cartesian space: after a large carry
// (half a turn of joint 1) that line runs through the base, the pull has no moment about joint 1,
// and the arm swings the long way round or stalls in a local minimum with the posture task
// (weight 1 against 1e4) unable to help. The leash keeps both tasks' targets consistent with one
// joint configuration q_l = q* + delta near the arm:
// - while dragging is on (full-body compliance), a joint further than `length` from q_l and moving
//   away from it takes q_l along at its own speed: a hand carrying the arm drags the leash, so the
//   springs' pull stays bounded (K times about `length`), and nothing steps when dragging starts;
// - always, q_l walks back to the posture target q* along a straight line in joint space at
//   `return_speed` (per joint, the largest component).
// The posture task tracks q* + delta; the end-effector task tracks T(q_l) T(q*)^-1 T*, which is
// T* itself once delta is zero. Continuous joints take the short way round. The offsets move
// continuously but carry no velocity feed-forward: the leash's speed switches between the walk
// and a dragging joint's, and a velocity step through the tasks' damping would step the torque;
// the damping's drag on the walk leaves the arm about D v / K behind, which closes at the end.
#include <phri/model/algorithms.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

namespace phri {

struct ReturnLeashSettings {
  double length_rad = 0.2;          ///< how far q_l may trail the arm (per joint)
  /// Walking speed of q_l back to q* (largest joint). Slow enough for Kinova's damped torque loops
  /// to follow with the wrist against friction: at 0.5 rad/s the arm fell behind the walk.
  double return_speed_rad_s = 0.15;
  /// Posture weight while q_l walks back (no hand on the arm). Both targets then come from one
  /// configuration, so weighting the posture like the end effector (ComplianceSettings::ee_weight)
  /// costs no conflict at the targets and makes the walk a joint-space motion: with the posture's
  /// usual weight 1 the end-effector task won every trade-off, and an arm carried through a
  /// straight elbow walked onto the other elbow branch of the same pose and stayed there.
  double walk_posture_weight = 1e4;
  /// [s] the posture weight moves between its usual value and walk_posture_weight geometrically
  /// over this time (a linear filter would multiply it by 100 in the first millisecond: a step).
  double weight_blend_s = 0.3;
};

class ReturnLeash {
public:
  /// Throws ConfigError unless length > 0 and return_speed > 0 (both finite).
  ReturnLeash(const Model& model, int frame_id, const ReturnLeashSettings& settings);

  /// Once per cycle. q, qd: measured; q_target, qd_target: the posture target. Computes the
  /// offsets below (kinematics only while the leash is out).
  void update(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& q_target,
              const Eigen::VectorXd& qd_target, bool dragging, double dt);
  /// Back to q* at once (a new start, a safe stop).
  void reset();

  /// True while q_l differs from q*.
  bool out() const { return out_; }
  /// delta = q_l - q*.
  const Eigen::VectorXd& offset() const { return offset_; }
  /// T(q_l) T(q*)^-1 (identity when in).
  const Eigen::Isometry3d& pose_offset() const { return pose_offset_; }
  const ReturnLeashSettings& settings() const { return settings_; }
  /// The posture task's weight this cycle: `usual` blended toward walk_posture_weight while q_l
  /// walks back with no hand on the arm.
  double posture_weight(double usual) const;

private:
  void drag(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& q_target,
            const Eigen::VectorXd& qd_target, double dt);
  void compute_pose_offset(const Model& model, const Eigen::VectorXd& q_target);

  ReturnLeashSettings settings_;
  int frame_id_;
  std::vector<bool> continuous_;
  Data scratch_;
  bool out_ = false;
  double walk_blend_ = 0.0;  ///< 0: usual posture weight, 1: walk_posture_weight
  Eigen::VectorXd offset_, previous_offset_, leash_q_;
  Eigen::Isometry3d pose_offset_ = Eigen::Isometry3d::Identity();
};

}  // namespace phri
