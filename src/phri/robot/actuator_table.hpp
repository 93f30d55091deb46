#pragma once
// phri::ActuatorTable: the per-joint drive models of a robot, loaded and validated from
// robots/<robot>/actuators.yaml (see the header of robots/kinova_gen3/actuators.yaml for the keys
// and units). Used by the simulated plant (SimRobot) and, later, by the low-level controller.
//
//   const auto table = phri::ActuatorTable::from_yaml_file("robots/kinova_gen3/actuators.yaml");
//   const double kt_gr = table[1].torque_per_amp();     // joint_2: 11 N.m/A
//
// Required per joint: name, torque_limit_Nm, velocity_limit_rad_s (what a maker publishes); the
// rest optional with the defaults of actuator_parameters.hpp (docs/robots.md), each default used
// listed by notices(). A Kinova drive needs them stated (RobotBundle, SimRobotConfig check it).
// Errors (missing/unknown keys, wrong types, out-of-range values, reflected inertia inconsistent
// with rotor inertia and gear ratio, static friction below Coulomb) throw phri::ConfigError with
// the key path, e.g. "joints[3].friction.coulomb_Nm".
#include <phri/robot/actuator_parameters.hpp>

#include <string>
#include <vector>

namespace phri {

class ActuatorTable {
public:
  static ActuatorTable from_yaml_file(const std::string& path);
  static ActuatorTable from_yaml_string(const std::string& yaml, const std::string& source_name = "<actuators>");

  ActuatorTable() = default;
  explicit ActuatorTable(std::vector<ActuatorParameters> joints) : joints_(std::move(joints)) {}

  int size() const { return static_cast<int>(joints_.size()); }
  const ActuatorParameters& operator[](int i) const { return joints_[static_cast<std::size_t>(i)]; }
  ActuatorParameters& operator[](int i) { return joints_[static_cast<std::size_t>(i)]; }
  const std::vector<ActuatorParameters>& joints() const { return joints_; }
  /// Index of the actuator of a joint, -1 when absent.
  int index_of(const std::string& joint_name) const;
  /// One line per optional key left out and the default used in its place, naming the joints
  /// (empty: every key stated). `source`: the file's name for the lines.
  std::vector<std::string> notices(const std::string& source) const;
  /// ConfigError naming `source` and joints[i].<key> of the first key left out: a drive whose
  /// loops run on the motor data (`why`, e.g. the Kinova emulation) needs every key stated.
  void require_stated(const std::string& source, const std::string& why) const;
  /// The actuators.yaml key of an ActuatorDefault bit (e.g. "gear_ratio").
  static const char* default_key(unsigned bit);

private:
  std::vector<ActuatorParameters> joints_;
};

}  // namespace phri
