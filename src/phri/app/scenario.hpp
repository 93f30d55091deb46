#pragma once
// The paper's scenarios as reference generators for the FSM (app/fsm.hpp), each a pure function
// of time, allocation-free once constructed:
//
//   static  — hold the arm extended: posture = the paper demo's postureTarget
//             [0, 0.58, 3.14, -1.84, 0, 0.85, 1.57] rad, end effector at its forward kinematics.
//             Reached by a minimum-jerk move (PoseMove for the end effector, JointMove for the
//             posture), then held: the FSM stops writing the target, so dual compliance may move it.
//   dynamic — the demo's "Sin" state (paper_parameters.md section 5): around the start pose p0,
//               z(t) = z0 + A sin(w t)                 A 0.10 m, w 3 rad/s
//               y(t) = y0 + triangle(t)                0.1 m/s between y0 - 0.40 and y0 + 0.05,
//                                                      starting at y0 toward -y
//             with two changes: the triangle's corners are rounded by a constant-acceleration
//             turn (SmoothTriangle; a true triangle steps the velocity), and both offsets fade in
//             through a quintic envelope s(t) over `ramp_s` (the motion starts at rest, from the
//             current target pose). Position, velocity and acceleration feed-forward are exact
//             derivatives: p = p0 + s f, v = s' f + s f', a = s'' f + 2 s' f' + s f''.
//             Orientation held.
//
// Also the motions between scenarios: JointMove (start-up to the home posture), PoseBrake and
// JointBrake (bring a moving reference to rest at a bounded deceleration with continuous velocity
// and acceleration, so no scenario change steps the reference or the feed-forward).
#include <phri/control/compliance_mode.hpp>
#include <phri/control/controller_targets.hpp>
#include <phri/model/model.hpp>
#include <phri/model/spatial.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <optional>
#include <string_view>
#include <vector>

namespace phri {

enum class Scenario { kStatic, kDynamic };
constexpr std::string_view to_string(Scenario s) { return s == Scenario::kStatic ? "static" : "dynamic"; }

/// The paper demo's postureTarget (NS and Sin states), joints 1..7 [rad].
inline std::vector<double> paper_posture_target() { return {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57}; }

struct StaticScenarioSettings {
  std::vector<double> posture_q_rad = paper_posture_target();  ///< held posture (one per joint)
  double move_speed_m_s = 0.1;          ///< peak EE speed of the move into the static pose
  double move_angular_speed_rad_s = 0.5;
  double min_move_duration_s = 1.0;
};

struct DynamicScenarioSettings {
  double vertical_amplitude_m = 0.10;          ///< A (world z)
  double vertical_angular_frequency_rad_s = 3.0;  ///< w
  double horizontal_speed_m_s = 0.10;          ///< cruise speed along world y
  double horizontal_min_offset_m = -0.40;      ///< y0 + this: far end (reached first)
  double horizontal_max_offset_m = 0.05;       ///< y0 + this: near end
  double horizontal_turn_acceleration_m_s2 = 0.5;  ///< rounds the triangle's corners
  double ramp_s = 2.0;                         ///< fade-in of both offsets
  std::optional<ComplianceMode> compliance;    ///< set on entry when given (paper: full-body)
};

/// How a moving reference is brought to rest (PoseBrake, JointBrake).
struct BrakeSettings {
  double linear_deceleration_m_s2 = 1.0;      ///< bound of the velocity term's deceleration
  double angular_deceleration_rad_s2 = 2.0;
  double joint_deceleration_rad_s2 = 1.0;     ///< joint-space references (start-up move)
  double min_duration_s = 0.2;                ///< keeps the jerk of the initial acceleration's fade bounded
};

/// Minimum-jerk (quintic) time scaling: s(0) = 0, s(1) = 1, zero velocity and acceleration at
/// both ends. Returns s, ds/dtau, d2s/dtau2 for tau in [0, 1] (clamped).
struct Quintic {
  double s = 0.0, ds = 0.0, dds = 0.0;
  static Quintic at(double tau);
  static constexpr double kPeakRate = 1.875;  ///< max ds/dtau
};

/// Back-and-forth along one axis between lo < hi at constant speed v, turning at constant
/// acceleration a (each turn takes 2 v / a and reaches v^2 / (2 a) beyond the straight part, all
/// within [lo, hi]). Starts at 0 (lo <= 0 <= hi) moving toward lo. Needs hi - lo >= v^2 / a.
class SmoothTriangle {
public:
  SmoothTriangle() = default;
  SmoothTriangle(double lo, double hi, double speed, double acceleration);
  /// Offset, velocity, acceleration at time t >= 0.
  void evaluate(double t, double& x, double& v, double& a) const;
  double period() const { return 2.0 * leg_; }

private:
  void leg(double tau, double& x, double& v, double& a) const;  // from hi toward lo, tau in [0, leg_)
  double lo_ = 0.0, hi_ = 0.0, speed_ = 0.0, accel_ = 1.0;
  double turn_ = 0.0;    // v / a
  double cruise_ = 0.0;  // straight-part duration
  double leg_ = 0.0;     // one way
  double phase_ = 0.0;   // time within the first leg where x = 0
};

class DynamicTrajectory {
public:
  explicit DynamicTrajectory(const DynamicScenarioSettings& settings = {});
  /// The centre p0 (and held orientation).
  void start(const Eigen::Isometry3d& centre) { centre_ = centre; }
  /// Reference at time t since start().
  void evaluate(double t, PoseReference& out) const;
  const DynamicScenarioSettings& settings() const { return settings_; }

private:
  DynamicScenarioSettings settings_;
  SmoothTriangle horizontal_;
  Eigen::Isometry3d centre_ = Eigen::Isometry3d::Identity();
};

/// Minimum-jerk move between two poses: straight line, and the geodesic for the orientation.
class PoseMove {
public:
  /// Duration: the longest of min_duration and what keeps the peak speeds within the bounds.
  void start(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double max_speed, double max_angular_speed,
             double min_duration);
  void evaluate(double t, PoseReference& out) const;
  double duration() const { return duration_; }
  const Eigen::Isometry3d& goal() const { return to_; }

private:
  Eigen::Isometry3d from_ = Eigen::Isometry3d::Identity(), to_ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d displacement_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_ = Eigen::Vector3d::Zero();  // log(R_to R_from^T), world axes
  double duration_ = 0.0;
};

/// Brings a moving reference to rest with continuous velocity AND acceleration: over a duration
/// T, velocity v(tau) = v0 h00(tau) + T a0 h10(tau) (cubic Hermite basis, tau = t / T), from (v0,
/// a0) at the start to (0, 0) at the end; position its integral. The velocity term decelerates at
/// most 1.5 |v0| / T, so T = max(min_duration, 1.5 |v0| / deceleration); the initial
/// acceleration a0 fades out within the same T. Per component of the twist; the orientation
/// integrates the angular part as a rotation vector (exact for a fixed axis; the brakes here start
/// from pure linear motion or a fixed-axis rotation).
struct HermiteBrake {
  struct Terms {
    double h = 0.0, dh = 0.0;  // velocity basis value and its derivative (per tau), for v0
    double g = 0.0, dg = 0.0;  // for T a0
    double H = 0.0, G = 0.0;   // integrals (per tau) of h and g
  };
  static Terms at(double tau);
  static constexpr double kPeakDeceleration = 1.5;  ///< max |dh/dtau|
};

class PoseBrake {
public:
  void start(const PoseReference& from, const BrakeSettings& settings);
  void evaluate(double t, PoseReference& out) const;
  double duration() const { return duration_; }

private:
  Eigen::Isometry3d from_ = Eigen::Isometry3d::Identity();
  Vector6d velocity_ = Vector6d::Zero(), acceleration_ = Vector6d::Zero();
  double duration_ = 0.0;
};

/// Joint-space references (posture task): quintic move and a brake. Continuous joints move the
/// short way round (the error wrapped to (-pi, pi]).
class JointMove {
public:
  explicit JointMove(const Model& model);
  void start(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double max_speed, double min_duration);
  void evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const;
  double duration() const { return duration_; }
  /// Difference to - from, wrapped for continuous joints (into `out`, sized).
  void difference(const Eigen::VectorXd& from, const Eigen::VectorXd& to, Eigen::VectorXd& out) const;

private:
  std::vector<bool> continuous_;
  Eigen::VectorXd from_, delta_;
  double duration_ = 0.0;
};

/// The same brake in joint space (every joint over the same time: the path keeps its shape).
class JointBrake {
public:
  explicit JointBrake(int nv)
      : from_(Eigen::VectorXd::Zero(nv)), velocity_(Eigen::VectorXd::Zero(nv)), acceleration_(Eigen::VectorXd::Zero(nv)) {}
  void start(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
             const BrakeSettings& settings);
  void evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const;
  double duration() const { return duration_; }

private:
  Eigen::VectorXd from_, velocity_, acceleration_;
  double duration_ = 0.0;
};

}  // namespace phri
