#include <phri/experiments/elastic_modes.hpp>

#include <phri/core/format.hpp>
#include <phri/sim/sim_robot.hpp>

#include <cmath>
#include <numbers>
#include <sstream>

namespace phri {

double two_mass_mode_hz(double k, double j_link, double j_rotor) {
  if (!(k > 0.0 && j_link > 0.0 && j_rotor > 0.0)) return 0.0;
  return std::sqrt(k * (1.0 / j_link + 1.0 / j_rotor)) / (2.0 * std::numbers::pi);
}

std::vector<ElasticJointMode> elastic_joint_modes(const SimRobot& robot) {
  std::vector<ElasticJointMode> modes;
  const SimRobotConfig& c = robot.config();
  if (!c.elasticity.enabled) return modes;
  const Eigen::VectorXd link = robot.joint_inertia_diagonal();
  for (int i = 0; i < robot.dof(); ++i) {
    ElasticJointMode m;
    m.joint = i + 1;
    m.stiffness_Nm_per_rad = c.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)];
    m.rotor_inertia_kgm2 = robot.plant_actuators()[i].reflected_inertia_kgm2;
    m.link_inertia_kgm2 = link[i];
    m.locked_link_hz = std::sqrt(m.stiffness_Nm_per_rad / m.rotor_inertia_kgm2) / (2.0 * std::numbers::pi);
    m.mode_hz = two_mass_mode_hz(m.stiffness_Nm_per_rad, m.link_inertia_kgm2, m.rotor_inertia_kgm2);
    modes.push_back(m);
  }
  return modes;
}

std::string elastic_modes_csv(const std::vector<ElasticJointMode>& modes) {
  std::ostringstream s;
  s << "joint,stiffness_Nm_per_rad,rotor_inertia_kgm2,link_inertia_kgm2,locked_link_hz,mode_hz\n";
  for (const ElasticJointMode& m : modes) {
    s << m.joint << ',' << format_fixed(m.stiffness_Nm_per_rad, 1) << ',' << format_fixed(m.rotor_inertia_kgm2, 5) << ','
      << format_fixed(m.link_inertia_kgm2, 5) << ',' << format_fixed(m.locked_link_hz, 3) << ',' << format_fixed(m.mode_hz, 3)
      << '\n';
  }
  return s.str();
}

}  // namespace phri
