#pragma once
// The paper's dynamic scenario (demo "Sin" state, paper_parameters.md section 5): around the
// start pose p0,
//   z(t) = z0 + A sin(w t)                 A 0.10 m, w 3 rad/s
//   y(t) = y0 + triangle(t)                0.1 m/s between y0 - 0.40 and y0 + 0.05, toward -y first
// with two changes: the triangle's corners are rounded by a constant-acceleration turn
// (SmoothTriangle; a true triangle steps the velocity), and both offsets fade in through a quintic
// envelope s(t) over `ramp_s` (the motion starts at rest). Position, velocity and acceleration
// feed-forward are exact derivatives: p = p0 + s f, v = s' f + s f', a = s'' f + 2 s' f' + s f''.
// Orientation held.
#include <phri/control/compliance_mode.hpp>
#include <phri/control/controller_targets.hpp>
#include <phri/trajectory/smooth_triangle.hpp>

#include <Eigen/Geometry>
#include <optional>

namespace phri {

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

}  // namespace phri
