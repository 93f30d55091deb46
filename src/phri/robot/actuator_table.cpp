#include <phri/core/yaml_reader.hpp>
#include <phri/robot/actuator_table.hpp>

#include <cmath>

namespace phri {
namespace {

ActuatorTable parse(const YamlReader& root) {
  root.allow_keys({"joints"});
  const YamlReader list = root.at("joints");
  if (!list.is_sequence() || list.size() == 0) throw list.error("", "expected a non-empty sequence of joints");
  std::vector<ActuatorParameters> joints;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader j = list.at(i);
    j.allow_keys({"name", "size", "gear_ratio", "torque_constant_Nm_per_A", "rotor_inertia_kgm2",
                  "reflected_inertia_kgm2", "current_limit_A", "torque_limit_Nm", "velocity_limit_rad_s",
                  "friction"});
    ActuatorParameters a;
    a.joint_name = j.text("name");
    for (const auto& other : joints) {
      if (other.joint_name == a.joint_name) throw j.error("name", "duplicate joint '" + a.joint_name + "'");
    }
    a.size = j.choice("size", {"large", "small"}) == "large" ? ActuatorSize::kLarge : ActuatorSize::kSmall;
    a.gear_ratio = j.number("gear_ratio", 1e-3, 1e5);
    a.torque_constant_Nm_per_A = j.number("torque_constant_Nm_per_A", 1e-6, 100.0);
    a.rotor_inertia_kgm2 = j.number("rotor_inertia_kgm2", 0.0, 1.0);
    a.reflected_inertia_kgm2 = j.number("reflected_inertia_kgm2", 0.0, 100.0);
    const double computed = a.rotor_inertia_kgm2 * a.gear_ratio * a.gear_ratio;
    if (std::abs(computed - a.reflected_inertia_kgm2) > 1e-3 * std::max(computed, 1e-12)) {
      throw j.error("reflected_inertia_kgm2", "differs from rotor_inertia_kgm2 * gear_ratio^2 = " +
                                                  std::to_string(computed));
    }
    a.current_limit_A = j.number("current_limit_A", 1e-6, 1e4);
    a.torque_limit_Nm = j.number("torque_limit_Nm", 1e-6, 1e5);
    a.velocity_limit_rad_s = j.number("velocity_limit_rad_s", 1e-6, 1e3);
    const YamlReader f = j.at("friction");
    f.allow_keys({"coulomb_Nm", "viscous_Nms_per_rad", "static_Nm", "velocity_threshold_rad_s",
                  "acceleration_threshold_rad_s2"});
    a.friction.coulomb_Nm = f.number("coulomb_Nm", 0.0, 1e3);
    a.friction.viscous_Nms_per_rad = f.number("viscous_Nms_per_rad", 0.0, 1e3);
    a.friction.static_Nm = f.number("static_Nm", 0.0, 1e3);
    if (a.friction.static_Nm < a.friction.coulomb_Nm) {
      throw f.error("static_Nm", "must be >= coulomb_Nm (breakaway friction is not below kinetic friction)");
    }
    a.friction.velocity_threshold_rad_s = f.number("velocity_threshold_rad_s", 0.0, 1e3);
    a.friction.acceleration_threshold_rad_s2 = f.number("acceleration_threshold_rad_s2", 0.0, 1e6);
    joints.push_back(a);
  }
  return ActuatorTable(std::move(joints));
}

}  // namespace

ActuatorTable ActuatorTable::from_yaml_file(const std::string& path) { return parse(YamlReader::load_file(path)); }

ActuatorTable ActuatorTable::from_yaml_string(const std::string& yaml, const std::string& source_name) {
  return parse(YamlReader::load_string(yaml, source_name));
}

int ActuatorTable::index_of(const std::string& joint_name) const {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    if (joints_[i].joint_name == joint_name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace phri
