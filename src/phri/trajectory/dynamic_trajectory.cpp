#include <phri/trajectory/dynamic_trajectory.hpp>

#include <phri/trajectory/quintic.hpp>

#include <cmath>

namespace phri {

DynamicTrajectory::DynamicTrajectory(const DynamicScenarioSettings& settings)
    : settings_(settings),
      horizontal_(settings.horizontal_min_offset_m, settings.horizontal_max_offset_m, settings.horizontal_speed_m_s,
                  settings.horizontal_turn_acceleration_m_s2) {}

void DynamicTrajectory::evaluate(double t, PoseReference& out) const {
  t = std::max(t, 0.0);
  double s = 1.0, ds = 0.0, dds = 0.0;
  if (settings_.ramp_s > 0.0) {
    const Quintic e = Quintic::at(t / settings_.ramp_s);
    s = e.s;
    ds = e.ds / settings_.ramp_s;
    dds = e.dds / (settings_.ramp_s * settings_.ramp_s);
  }
  const double amplitude = settings_.vertical_amplitude_m, w = settings_.vertical_angular_frequency_rad_s;
  const double sine = std::sin(w * t), cosine = std::cos(w * t);
  Eigen::Vector3d f(0.0, 0.0, amplitude * sine), fd(0.0, 0.0, amplitude * w * cosine),
      fdd(0.0, 0.0, -amplitude * w * w * sine);
  horizontal_.evaluate(t, f.y(), fd.y(), fdd.y());
  out.pose = centre_;
  out.pose.translation() += s * f;
  out.velocity.head<3>() = ds * f + s * fd;
  out.acceleration.head<3>() = dds * f + 2.0 * ds * fd + s * fdd;
  out.velocity.tail<3>().setZero();
  out.acceleration.tail<3>().setZero();
}

}  // namespace phri
