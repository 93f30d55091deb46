#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/robot/actuator_table.hpp>

#include <algorithm>
#include <cmath>

namespace phri {
namespace {

// Physical ranges of a joint drive (the reason for each bound next to it).
// Gear ratio: harmonic and planetary gears of robot joints are 30..320 (the Gen3's 100); 1 is a
// direct drive, above 1000 no joint gearbox.
constexpr double kMinGearRatio = 1.0, kMaxGearRatio = 1000.0;
// Motor torque constant K_T (motor side): 1e-3..10 N.m/A spans motors from a few W to a few kW
// (the Gen3's 0.11 / 0.076).
constexpr double kMinTorqueConstant = 1e-3, kMaxTorqueConstant = 10.0;
// Rotor inertia (motor side): up to 1e-2 kg.m^2, a motor of several kW (the Gen3's 3e-6).
constexpr double kMaxRotorInertia = 1e-2;
// Motor current: 100 A is a kW motor at 48 V; a collaborative arm's drives run at ~10 A
// (the Gen3's limits here: 9.5 / 6.8 A). 1e4 A is a unit mistake.
constexpr double kMaxCurrent_A = 100.0;
// The QP's torque bound: at least 0.1 N.m (below, the drive cannot even hold the link's weight or
// overcome its own friction), at most what the motor can produce (checked below).
constexpr double kMinTorqueLimit_Nm = 0.1;
// Joint velocity: 10 rad/s is ~570 deg/s, beyond any collaborative arm (the Gen3's 2.1 / 3.05
// rad/s); 120 is a degrees-per-second value typed as rad/s.
constexpr double kMaxJointVelocity_rad_s = 10.0;
// Friction torques up to 100 N.m and viscous 100 N.m.s/rad (the Gen3's ~2 and ~2); thresholds of
// the friction model up to 1 rad/s and 100 rad/s^2 (the Gen3's 0.1 and 1).
constexpr double kMaxFriction_Nm = 100.0;
// Reflected rotor inertia at the joint when neither it nor the rotor's is given [kg.m^2]: a cobot
// joint's order (the Gen3's 0.03 on its large joints); the plant's stick-slip model needs >= 1e-3.
constexpr double kDefaultReflectedInertia_kgm2 = 0.01;

void parse_friction(const YamlReader& f, ActuatorParameters& a, FrictionParameters& out) {
  f.allow_keys({"coulomb_Nm", "viscous_Nms_per_rad", "static_Nm", "velocity_threshold_rad_s",
                "acceleration_threshold_rad_s2"});
  for (const char* key : {"coulomb_Nm", "viscous_Nms_per_rad", "static_Nm", "velocity_threshold_rad_s",
                          "acceleration_threshold_rad_s2"}) {
    if (!f.has(key)) a.defaulted |= kDefaultedFriction;
  }
  // Unknown friction: none (0), static as Coulomb; `phri identify-friction` measures it.
  out.coulomb_Nm = f.number_or("coulomb_Nm", 0.0, 0.0, kMaxFriction_Nm);
  out.viscous_Nms_per_rad = f.number_or("viscous_Nms_per_rad", 0.0, 0.0, kMaxFriction_Nm);
  out.static_Nm = f.number_or("static_Nm", out.coulomb_Nm, 0.0, kMaxFriction_Nm);
  if (out.static_Nm < out.coulomb_Nm) {
    throw f.error("static_Nm", "must be >= coulomb_Nm (breakaway friction is not below kinetic friction)");
  }
  // A drive whose breakaway friction it cannot overcome never moves.
  if (!(out.static_Nm < a.max_motor_torque_Nm())) {
    throw f.error("static_Nm", "must be below the drive's maximum torque " + format_general(a.max_motor_torque_Nm(), 6) +
                                   " N.m (current_limit_A x K_T x G_r)");
  }
  out.velocity_threshold_rad_s = f.number_or("velocity_threshold_rad_s", kDefaultVelocityThreshold_rad_s, 0.0, 1.0);
  out.acceleration_threshold_rad_s2 = f.number_or("acceleration_threshold_rad_s2", kDefaultAccelerationThreshold_rad_s2, 0.0, 100.0);
}

// The limits: the current within kMaxCurrent_A, the torque bound within what that current gives.
void parse_limits(const YamlReader& j, ActuatorParameters& a) {
  a.torque_limit_Nm = j.number("torque_limit_Nm", kMinTorqueLimit_Nm, 1e5);
  if (j.has("current_limit_A")) {
    a.current_limit_A = j.number("current_limit_A", 1e-3, kMaxCurrent_A);
  } else {  // the drive's peak a little above the controller's bound (the Gen3's 105 vs 95 N.m)
    a.defaulted |= kDefaultedCurrentLimit;
    a.current_limit_A = kDefaultCurrentHeadroom * a.torque_limit_Nm / a.torque_per_amp();
  }
  if (a.torque_limit_Nm > a.max_motor_torque_Nm() * (1.0 + 1e-9)) {
    throw j.error("torque_limit_Nm", format_general(a.torque_limit_Nm, 6) + " N.m exceeds the drive's maximum " +
                                         format_general(a.max_motor_torque_Nm(), 6) +
                                         " N.m (current_limit_A x torque_constant_Nm_per_A x gear_ratio)");
  }
  a.velocity_limit_rad_s = j.number("velocity_limit_rad_s", 1e-3, kMaxJointVelocity_rad_s);
}

ActuatorParameters parse_joint(const YamlReader& j) {
  j.allow_keys({"name", "size", "gear_ratio", "torque_constant_Nm_per_A", "rotor_inertia_kgm2", "reflected_inertia_kgm2",
                "current_limit_A", "torque_limit_Nm", "velocity_limit_rad_s", "transmission_stiffness_Nm_per_rad", "friction"});
  ActuatorParameters a;
  a.joint_name = j.text("name");
  // Optional: Kinova's actuator class. Absent, what it selects is derived from the drive's own data
  // (ActuatorParameters::size_class, default_compliance_deadband_Nm).
  if (j.has("size")) a.size = j.choice("size", {"large", "small"}) == "large" ? ActuatorSize::kLarge : ActuatorSize::kSmall;
  // Optional (a maker rarely publishes them): the defaults of actuator_parameters.hpp, each noted.
  auto optional = [&](const char* key, unsigned bit, double fallback, double lo, double hi) {
    if (!j.has(key)) a.defaulted |= bit;
    return j.number_or(key, fallback, lo, hi);
  };
  a.gear_ratio = optional("gear_ratio", kDefaultedGearRatio, kDefaultGearRatio, kMinGearRatio, kMaxGearRatio);
  a.torque_constant_Nm_per_A = optional("torque_constant_Nm_per_A", kDefaultedTorqueConstant, kDefaultTorqueConstant_Nm_per_A,
                                        kMinTorqueConstant, kMaxTorqueConstant);
  // Rotor inertia unknown: kDefaultReflectedInertia_kgm2 at the joint; reflected = rotor x G_r^2 when only one is given.
  const double max_reflected = kMaxRotorInertia * kMaxGearRatio * kMaxGearRatio;
  const bool rotor = j.has("rotor_inertia_kgm2"), reflected = j.has("reflected_inertia_kgm2");
  a.rotor_inertia_kgm2 = rotor      ? j.number("rotor_inertia_kgm2", 0.0, kMaxRotorInertia)
                         : reflected ? j.number("reflected_inertia_kgm2", 0.0, max_reflected) / (a.gear_ratio * a.gear_ratio)
                                     : kDefaultReflectedInertia_kgm2 / (a.gear_ratio * a.gear_ratio);
  a.reflected_inertia_kgm2 = reflected ? j.number("reflected_inertia_kgm2", 0.0, max_reflected)
                                       : a.rotor_inertia_kgm2 * a.gear_ratio * a.gear_ratio;
  if (!rotor) a.defaulted |= kDefaultedRotorInertia;
  if (!reflected) a.defaulted |= kDefaultedReflectedInertia;
  const double computed = a.rotor_inertia_kgm2 * a.gear_ratio * a.gear_ratio;
  if (std::abs(computed - a.reflected_inertia_kgm2) > 1e-3 * std::max(computed, 1e-12)) {
    throw j.error("reflected_inertia_kgm2", "differs from rotor_inertia_kgm2 * gear_ratio^2 = " + std::to_string(computed));
  }
  parse_limits(j, a);
  // Optional: 0 (rigid) when absent. Harmonic drives are 1e3..1e6 N.m/rad.
  if (j.has("transmission_stiffness_Nm_per_rad")) {
    a.transmission_stiffness_Nm_per_rad = j.number("transmission_stiffness_Nm_per_rad", 10.0, 1e8);
  }
  if (j.has("friction")) {
    parse_friction(j.at("friction"), a, a.friction);
  } else {
    a.defaulted |= kDefaultedFriction;
    a.friction.static_Nm = a.friction.coulomb_Nm = a.friction.viscous_Nms_per_rad = 0.0;
    a.friction.velocity_threshold_rad_s = kDefaultVelocityThreshold_rad_s;
    a.friction.acceleration_threshold_rad_s2 = kDefaultAccelerationThreshold_rad_s2;
  }
  return a;
}

ActuatorTable parse(const YamlReader& root) {
  root.allow_keys({"joints"});
  const YamlReader list = root.at("joints");
  if (!list.is_sequence() || list.size() == 0) throw list.error("", "expected a non-empty sequence of joints");
  std::vector<ActuatorParameters> joints;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader j = list.at(i);
    ActuatorParameters a = parse_joint(j);
    for (const auto& other : joints) {
      if (other.joint_name == a.joint_name) throw j.error("name", "duplicate joint '" + a.joint_name + "'");
    }
    joints.push_back(a);
  }
  return ActuatorTable(std::move(joints));
}

}  // namespace

ActuatorTable ActuatorTable::from_yaml_file(const std::string& path) { return parse(YamlReader::load_file(path)); }

ActuatorTable ActuatorTable::from_yaml_string(const std::string& yaml, const std::string& source_name) {
  return parse(YamlReader::load_string(yaml, source_name));
}

const char* ActuatorTable::default_key(unsigned bit) {
  switch (bit) {
    case kDefaultedGearRatio: return "gear_ratio";
    case kDefaultedTorqueConstant: return "torque_constant_Nm_per_A";
    case kDefaultedRotorInertia: return "rotor_inertia_kgm2";
    case kDefaultedReflectedInertia: return "reflected_inertia_kgm2";
    case kDefaultedCurrentLimit: return "current_limit_A";
    case kDefaultedFriction: return "friction";
  }
  return "?";
}

void ActuatorTable::require_stated(const std::string& source, const std::string& why) const {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    for (int b = 0; b < kActuatorDefaultCount; ++b) {
      const unsigned bit = 1u << b;
      if (joints_[i].defaulted & bit) {
        throw ConfigError(source, "joints[" + std::to_string(i) + "]." + default_key(bit),
                          "missing: " + why + " (only a generic drive may leave it out)");
      }
    }
  }
}

std::vector<std::string> ActuatorTable::notices(const std::string& source) const {
  static const char* const kUsed[kActuatorDefaultCount] = {
      "100 used", "0.1 N.m/A used", "0.01 kg.m^2 / gear_ratio^2 used (0.01 kg.m^2 at the joint)",
      "rotor_inertia_kgm2 x gear_ratio^2 used",
      "1.1 x torque_limit_Nm / (torque_constant_Nm_per_A x gear_ratio) used",
      "no friction (0; static = Coulomb; thresholds 0.1 rad/s, 1 rad/s^2) where not given; phri identify-friction measures it"};
  std::vector<std::string> out;
  for (int b = 0; b < kActuatorDefaultCount; ++b) {
    const unsigned bit = 1u << b;
    std::string joints;
    for (const ActuatorParameters& a : joints_) {
      if (a.defaulted & bit) joints += (joints.empty() ? "" : ", ") + a.joint_name;
    }
    if (!joints.empty()) out.push_back(source + ": " + default_key(bit) + " not given (" + joints + "): " + kUsed[b]);
  }
  return out;
}

int ActuatorTable::index_of(const std::string& joint_name) const {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    if (joints_[i].joint_name == joint_name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace phri
