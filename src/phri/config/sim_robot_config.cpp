#include <phri/core/discrete_transfer_function.hpp>
#include <phri/core/format.hpp>
#include <phri/core/random_generator.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/config/sim_robot_config.hpp>

#include <cmath>
#include <filesystem>

namespace phri {
namespace {

// Random stream of the drive-gain mismatch (SimRobot uses stream 3 of the same seed for the links).
constexpr std::uint64_t kTorqueConstantMismatchStream = 4;

constexpr double kHuge = 1e9;

// Physical ranges (the reason for each bound next to it).
// A joint position beyond one turn each way is a typo (degrees for radians), not a posture.
constexpr double kMaxJointAngle_rad = 2.0 * 3.14159265358979323846;
// What the arm may carry at its flange: 20 kg, 5x the Gen3's rated 4 kg payload; a drop-test mass
// or a tool above it is a unit mistake (g for kg), and the drives could not hold it anyway.
constexpr double kMaxCarriedMass_kg = 20.0;
// Principal moments of a carried body: 1 kg.m^2 is 20 kg at a 0.22 m radius of gyration.
constexpr double kMaxCarriedInertia_kgm2 = 1.0;
// An encoder coarser than 12 bits per joint turn (1.5 mrad) is no arm encoder: the Gen3's is
// ~2^18; a quantum of radians would make the velocity estimate and the position loop meaningless.
constexpr double kMinEncoderCounts = 4096.0;
// Vendor position servo: the defaults are 12000 / 3000 N.m/rad (robots/kinova_gen3/README.md).
// 50000 N.m/rad is about the torsional stiffness of a harmonic drive of this size: a servo cannot
// be stiffer than the gearbox it acts through. Kd, Ki scaled alike (defaults 150 / 60000).
constexpr double kMaxVendorKp_Nm_per_rad = 5.0e4;
constexpr double kMaxVendorKd_Nms_per_rad = 1.0e3;
constexpr double kMaxVendorKi_Nm_per_rad_s = 5.0e5;
// Vendor torque loop's velocity damping (defaults 15 / 5): 100 N.m.s/rad is 20x the viscous friction.
constexpr double kMaxVendorDamping_Nms_per_rad = 100.0;
// Coefficients of the vendor filter H(z): the paper's are below 2 in magnitude; a stable filter of
// order <= 5 normalised by a0 has |a_i| <= C(5, i) <= 10.
constexpr double kMaxFilterCoefficient = 10.0;

ExternalForce::Profile parse_profile(const std::string& name) {
  if (name == "step") return ExternalForce::Profile::kStep;
  if (name == "ramp") return ExternalForce::Profile::kRamp;
  return ExternalForce::Profile::kHalfSine;
}

// ---- one parser per section of `plant:`, in the order parse() reads them

void parse_robot_files(const YamlReader& r, const std::string& base_dir, SimRobotConfig& c) {
  r.allow_keys({"mjcf", "urdf", "locked_joints", "balance_inertia", "actuators"});
  // The arm: a hand-written MJCF, or the URDF the plant is generated from (not both).
  if (r.has("mjcf") == r.has("urdf")) throw r.error("urdf", "give exactly one of 'mjcf' and 'urdf'");
  if (r.has("mjcf")) {
    c.mjcf_path = resolve_path(base_dir, r.text("mjcf"), PathForm::kAsGiven);
  } else {
    c.urdf_path = resolve_path(base_dir, r.text("urdf"), PathForm::kAsGiven);
    c.balance_inertia = r.boolean_or("balance_inertia", false);
    if (r.has("locked_joints")) {
      const YamlReader list = r.at("locked_joints");
      list.expect_sequence();
      for (std::size_t i = 0; i < list.size(); ++i) c.locked_joints.push_back(list.at(i).as_text());
    }
  }
  if (!r.has("urdf") && (r.has("balance_inertia") || r.has("locked_joints"))) {
    throw r.error(r.has("locked_joints") ? "locked_joints" : "balance_inertia", "applies to a plant generated from 'urdf' only");
  }
  c.actuators_path = resolve_path(base_dir, r.text("actuators"), PathForm::kAsGiven);
  c.actuators = ActuatorTable::from_yaml_file(c.actuators_path);
}

void parse_timing(const YamlReader& t, SimRobotConfig& c) {
  t.allow_keys({"physics_rate_Hz", "control_period_s"});
  c.physics_rate_Hz = t.number_or("physics_rate_Hz", c.physics_rate_Hz, 1000.0, 100000.0);
  c.control_period_s = t.number_or("control_period_s", c.control_period_s, 1e-4, 0.1);
}

std::vector<double> parse_initial_q(const YamlReader& init, int n) {
  init.allow_keys({"q_rad"});
  return init.per_joint("q_rad", n, -kMaxJointAngle_rad, kMaxJointAngle_rad);
}

SimRobotConfig::ActuatorOverride parse_actuator_override(const YamlReader& j, const std::string& joint) {
  j.allow_keys({"coulomb_Nm", "viscous_Nms_per_rad", "static_Nm", "reflected_inertia_kgm2", "torque_constant_scale"});
  SimRobotConfig::ActuatorOverride ov;
  ov.joint = joint;
  // The ranges of actuators.yaml (robot/actuator_table.cpp): friction up to 100 N.m or N.m.s/rad,
  // reflected inertia up to 10 kg.m^2 (the Gen3's 0.03); a true K_T within a factor 2 of the
  // nominal one (a spread beyond is another motor, not a tolerance).
  if (j.has("coulomb_Nm")) ov.coulomb_Nm = j.number("coulomb_Nm", 0.0, 100.0);
  if (j.has("viscous_Nms_per_rad")) ov.viscous_Nms_per_rad = j.number("viscous_Nms_per_rad", 0.0, 100.0);
  if (j.has("static_Nm")) ov.static_Nm = j.number("static_Nm", 0.0, 100.0);
  if (j.has("reflected_inertia_kgm2")) ov.reflected_inertia_kgm2 = j.number("reflected_inertia_kgm2", 0.0, 10.0);
  if (j.has("torque_constant_scale")) ov.torque_constant_scale = j.number("torque_constant_scale", 0.5, 2.0);
  return ov;
}

void parse_actuator_overrides(const YamlReader& o, SimRobotConfig& c) {
  o.expect_map();
  for (const auto& a : c.actuators.joints()) {
    if (o.has(a.joint_name)) c.actuator_overrides.push_back(parse_actuator_override(o.at(a.joint_name), a.joint_name));
  }
  // Any key that is not a joint of actuators.yaml is an error.
  for (const std::string& key : o.keys()) {
    if (c.actuators.index_of(key) < 0) throw o.error(key, "unknown joint (not in " + c.actuators_path + ")");
  }
}

void parse_friction(const YamlReader& f, SimRobotConfig::Friction& s) {
  f.allow_keys({"breakaway_velocity_rad_s", "stribeck_velocity_rad_s", "stribeck_exponent", "ripple_fraction",
                "ripple_cycles_per_rev", "ripple_phase_rad"});
  s.breakaway_velocity_rad_s = f.number_or("breakaway_velocity_rad_s", 1e-3, 1e-6, 1.0);
  // The sliding form (StickSlipFriction): v_s 0 (off) to 1 rad/s, delta 0.5..4 (Stribeck exponents
  // reported in the literature lie in 0.5..2), ripple below half the Coulomb level (the level stays > 0).
  s.stribeck_velocity_rad_s = f.number_or("stribeck_velocity_rad_s", s.stribeck_velocity_rad_s, 0.0, 1.0);
  s.stribeck_exponent = f.number_or("stribeck_exponent", s.stribeck_exponent, 0.5, 4.0);
  s.ripple_fraction = f.number_or("ripple_fraction", s.ripple_fraction, 0.0, 0.5);
  s.ripple_cycles_per_rev = f.number_or("ripple_cycles_per_rev", s.ripple_cycles_per_rev, 0.0, 10000.0);
  s.ripple_phase_rad = f.number_or("ripple_phase_rad", s.ripple_phase_rad, -7.0, 7.0);
}

void parse_noise(const YamlReader& z, int n, SimRobotConfig::Noise& s) {
  z.allow_keys({"torque_sensor_std_Nm", "torque_sensor_offset_Nm", "velocity_std_rad_s", "current_std_A",
                "encoder_counts_per_rev"});
  // Sensor noise and offsets: at most a few N.m / 0.1 rad/s / 1 A (the Gen3's are ~0.05 N.m,
  // 0.002 rad/s, 0.01 A): more is a broken sensor, not noise.
  s.torque_sensor_std_Nm = z.number_or("torque_sensor_std_Nm", s.torque_sensor_std_Nm, 0.0, 2.0);
  if (z.has("torque_sensor_offset_Nm")) s.torque_sensor_offset_Nm = z.per_joint("torque_sensor_offset_Nm", n, -5.0, 5.0);
  s.velocity_std_rad_s = z.number_or("velocity_std_rad_s", s.velocity_std_rad_s, 0.0, 0.1);
  s.current_std_A = z.number_or("current_std_A", s.current_std_A, 0.0, 1.0);
  // 0: no quantisation (tests); otherwise at least kMinEncoderCounts, at most 2^32.
  s.encoder_counts_per_rev = z.number_or("encoder_counts_per_rev", s.encoder_counts_per_rev, 0.0, 4294967296.0);
  if (s.encoder_counts_per_rev != 0.0 && s.encoder_counts_per_rev < kMinEncoderCounts) {
    throw z.error("encoder_counts_per_rev", "must be 0 (no quantisation) or >= 4096 (12 bits per turn; the Gen3's "
                                            "is ~2^18), got " + std::to_string(s.encoder_counts_per_rev));
  }
}

void parse_ft_sensor(const YamlReader& f, SimRobotConfig::FtSensor& s) {
  f.allow_keys({"flange_site", "sensor_offset_m", "sensor_xyz_m", "sensor_rpy_rad", "flange_side_mass_kg", "flange_side_com_m",
                "flange_side_inertia_kgm2", "rate_Hz", "force_std_N", "torque_std_Nm", "force_bias_N", "torque_bias_Nm"});
  // The mount and the bodies have no default: they are the arm's (robots/<robot>/robot.yaml says them too).
  s.flange_site = f.text("flange_site");
  s.sensor_mount = read_sensor_mount(f, "sensor_offset_m", "sensor_xyz_m", "sensor_rpy_rad");
  s.flange_side_mass_kg = f.number("flange_side_mass_kg", 1e-4, kMaxCarriedMass_kg);
  s.flange_side_com_m = f.vector3("flange_side_com_m", -0.5, 0.5);
  s.flange_side_inertia_kgm2 = f.vector3("flange_side_inertia_kgm2", 1e-9, kMaxCarriedInertia_kgm2);
  s.rate_Hz = f.number_or("rate_Hz", s.rate_Hz, 1.0, 100000.0);
  // Noise and bias: within the SensONE's range (~±500 N, ±10 N.m) and far above its datasheet noise.
  s.force_std_N = f.number_or("force_std_N", s.force_std_N, 0.0, 10.0);
  s.torque_std_Nm = f.number_or("torque_std_Nm", s.torque_std_Nm, 0.0, 1.0);
  s.force_bias_N = f.vector3_or("force_bias_N", s.force_bias_N, -100.0, 100.0);
  s.torque_bias_Nm = f.vector3_or("torque_bias_Nm", s.torque_bias_Nm, -10.0, 10.0);
}

// `with_sensor`: below an F/T sensor (its section places it); otherwise on the flange, whose site
// the tool section names.
void parse_tool(const YamlReader& t, bool with_sensor, SimRobotConfig& c) {
  SimRobotConfig::Tool& s = c.tool;
  if (with_sensor) {
    t.allow_keys({"mass_kg", "com_m", "inertia_kgm2"});
  } else {
    t.allow_keys({"flange_site", "mass_kg", "com_m", "inertia_kgm2"});
    c.ft_sensor.flange_site = t.text("flange_site");
  }
  s.mass_kg = t.number("mass_kg", 1e-4, kMaxCarriedMass_kg);
  s.com_m = t.vector3("com_m", -0.5, 0.5);
  s.inertia_kgm2 = t.vector3("inertia_kgm2", 1e-9, kMaxCarriedInertia_kgm2);
}

void parse_mismatch(const YamlReader& m, SimRobotConfig::Mismatch& s) {
  m.allow_keys({"enabled", "seed", "mass_fraction", "com_fraction", "inertia_fraction", "torque_constant_fraction"});
  s.enabled = m.boolean_or("enabled", false);
  s.seed = static_cast<std::uint64_t>(m.integer_or("seed", 7, 0, (1LL << 62)));
  s.mass_fraction = m.number_or("mass_fraction", s.mass_fraction, 0.0, 0.5);
  s.com_fraction = m.number_or("com_fraction", s.com_fraction, 0.0, 0.5);
  s.inertia_fraction = m.number_or("inertia_fraction", s.inertia_fraction, 0.0, 0.5);
  s.torque_constant_fraction = m.number_or("torque_constant_fraction", s.torque_constant_fraction, 0.0, 0.5);
}

// vendor.position: the gains of the vendor's position loop, one per joint.
void parse_vendor_position(const YamlReader& pos, int n, SimRobotConfig::Vendor& v) {
  pos.allow_keys({"kp_Nm_per_rad", "kd_Nms_per_rad", "ki_Nm_per_rad_s", "integral_limit_Nm"});
  if (pos.has("kp_Nm_per_rad")) v.position_kp_Nm_per_rad = pos.per_joint("kp_Nm_per_rad", n, 0.0, kMaxVendorKp_Nm_per_rad);
  if (pos.has("kd_Nms_per_rad")) v.position_kd_Nms_per_rad = pos.per_joint("kd_Nms_per_rad", n, 0.0, kMaxVendorKd_Nms_per_rad);
  if (pos.has("ki_Nm_per_rad_s")) {
    v.position_ki_Nm_per_rad_s = pos.per_joint("ki_Nm_per_rad_s", n, 0.0, kMaxVendorKi_Nm_per_rad_s);
  }
  // At most the drive's torque: checked against actuators.yaml in validate().
  if (pos.has("integral_limit_Nm")) v.position_integral_limit_Nm = pos.per_joint("integral_limit_Nm", n, 0.0, 1e4);
}

// vendor.torque: the vendor's torque loop, one value per joint.
void parse_vendor_torque(const YamlReader& t, int n, SimRobotConfig::Vendor& v) {
  t.allow_keys({"feedback_gain", "velocity_damping_Nms_per_rad"});
  if (t.has("feedback_gain")) v.torque_feedback_gain = t.per_joint("feedback_gain", n, 0.0, 0.95);
  if (t.has("velocity_damping_Nms_per_rad")) {
    v.torque_velocity_damping_Nms_per_rad = t.per_joint("velocity_damping_Nms_per_rad", n, 0.0, kMaxVendorDamping_Nms_per_rad);
  }
}

// vendor.torque_high_velocity: the filter of the high-velocity torque loop.
void parse_vendor_high_velocity(const YamlReader& h, SimRobotConfig::Vendor& v) {
  h.allow_keys({"numerator", "denominator", "rate_Hz"});
  if (h.has("numerator")) v.high_velocity_numerator = h.numbers("numerator", -1, -kMaxFilterCoefficient, kMaxFilterCoefficient);
  if (h.has("denominator")) {
    v.high_velocity_denominator = h.numbers("denominator", -1, -kMaxFilterCoefficient, kMaxFilterCoefficient);
  }
  v.high_velocity_rate_Hz = h.number_or("rate_Hz", v.high_velocity_rate_Hz, 1.0, 100000.0);
}

void parse_vendor(const YamlReader& r, int n, SimRobotConfig::Vendor& v) {
  r.allow_keys({"position", "torque", "torque_high_velocity"});
  if (r.has("position")) parse_vendor_position(r.at("position"), n, v);
  if (r.has("torque")) parse_vendor_torque(r.at("torque"), n, v);
  if (r.has("torque_high_velocity")) parse_vendor_high_velocity(r.at("torque_high_velocity"), v);
}

void parse_drop_test(const YamlReader& d, SimRobotConfig::DropTest& s) {
  d.allow_keys({"enabled", "mass_kg", "radius_m", "cable_length_m", "cable_stiffness_N_per_m", "cable_damping_Ns_per_m",
                "anchor_m", "release_time_s", "latch_stiffness_N_per_m", "release_vertical_spread_m",
                "release_horizontal_spread_m", "held_by_hand"});
  s.enabled = d.boolean_or("enabled", false);
  s.mass_kg = d.number_or("mass_kg", s.mass_kg, 1e-3, kMaxCarriedMass_kg);
  s.radius_m = d.number_or("radius_m", s.radius_m, 1e-3, 0.5);
  s.cable_length_m = d.number_or("cable_length_m", s.cable_length_m, 0.0, 2.0);  // the arm's reach is ~1 m
  s.cable_stiffness_N_per_m = d.number_or("cable_stiffness_N_per_m", s.cable_stiffness_N_per_m, 1.0, 1e7);
  s.cable_damping_Ns_per_m = d.number_or("cable_damping_Ns_per_m", s.cable_damping_Ns_per_m, 0.0, 1e5);
  s.anchor_m = d.vector3_or("anchor_m", s.anchor_m, -1.0, 1.0);
  s.release_time_s = d.number_or("release_time_s", s.release_time_s, 0.0, kHuge);
  s.latch_stiffness_N_per_m = d.number_or("latch_stiffness_N_per_m", s.latch_stiffness_N_per_m, 1.0, 1e7);
  // A hand, not a throw: a few centimetres at most (and never past the cable's length).
  s.release_vertical_spread_m = d.number_or("release_vertical_spread_m", s.release_vertical_spread_m, 0.0, 0.1);
  s.release_horizontal_spread_m = d.number_or("release_horizontal_spread_m", s.release_horizontal_spread_m, 0.0, 0.1);
  s.held_by_hand = d.boolean_or("held_by_hand", s.held_by_hand);
}

void parse_floor(const YamlReader& f, SimRobotConfig::Floor& s) {
  f.allow_keys({"enabled", "height_m", "tool_contact"});
  s.enabled = f.boolean_or("enabled", false);
  s.height_m = f.number_or("height_m", 0.0, -2.0, 2.0);  // within the arm's reach of its base
  s.tool_contact = f.boolean_or("tool_contact", false);
}

// One entry of `disturbances:`.
ExternalForce parse_disturbance(const YamlReader& e) {
  e.allow_keys({"body", "point_m", "frame", "force_N", "torque_Nm", "profile", "start_s", "duration_s", "rise_s"});
  ExternalForce f;
  f.body = e.text("body");
  f.point_m = e.vector3_or("point_m", Eigen::Vector3d::Zero(), -2.0, 2.0);  // on the body: within the arm's size
  f.frame = e.choice_or("frame", "world", {"world", "local"}) == "world" ? ExternalForce::Frame::kWorld
                                                                        : ExternalForce::Frame::kLocal;
  // A person pushes with a few hundred N at most; 1000 N / 100 N.m is already a hard impact.
  f.force_N = e.vector3_or("force_N", Eigen::Vector3d::Zero(), -1e3, 1e3);
  f.torque_Nm = e.vector3_or("torque_Nm", Eigen::Vector3d::Zero(), -100.0, 100.0);
  f.profile = parse_profile(e.choice("profile", {"step", "ramp", "half_sine"}));
  f.start_s = e.number("start_s", 0.0, kHuge);
  f.duration_s = e.number("duration_s", 1e-6, kHuge);
  f.rise_s = e.number_or("rise_s", f.duration_s, 0.0, kHuge);
  if (f.profile == ExternalForce::Profile::kRamp && f.rise_s > f.duration_s) {
    throw e.error("rise_s", "must not exceed duration_s");
  }
  return f;
}

std::vector<ExternalForce> parse_disturbances(const YamlReader& list) {
  list.expect_sequence();
  std::vector<ExternalForce> out;
  for (std::size_t i = 0; i < list.size(); ++i) out.push_back(parse_disturbance(list.at(i)));
  return out;
}

void parse_random_pushes(const YamlReader& r, RandomPushSettings& s) {
  r.allow_keys({"enabled", "links", "start_s", "min_interval_s", "max_interval_s", "min_force_N", "max_force_N",
                "min_duration_s", "max_duration_s", "profile"});
  s.enabled = r.boolean_or("enabled", false);
  if (r.has("links")) {
    const YamlReader links = r.at("links");
    links.expect_sequence();
    for (std::size_t i = 0; i < links.size(); ++i) s.links.push_back(links.at(i).as_text());
  }
  s.start_s = r.number_or("start_s", s.start_s, 0.0, kHuge);
  s.min_interval_s = r.number_or("min_interval_s", s.min_interval_s, 0.0, kHuge);
  s.max_interval_s = r.number_or("max_interval_s", s.max_interval_s, 0.0, kHuge);
  s.min_force_N = r.number_or("min_force_N", s.min_force_N, 0.0, 1000.0);
  s.max_force_N = r.number_or("max_force_N", s.max_force_N, 0.0, 1000.0);
  s.min_duration_s = r.number_or("min_duration_s", s.min_duration_s, 1e-3, 10.0);
  s.max_duration_s = r.number_or("max_duration_s", s.max_duration_s, 1e-3, 10.0);
  s.profile = parse_profile(r.choice_or("profile", "half_sine", {"step", "ramp", "half_sine"}));
  if (s.max_interval_s < s.min_interval_s) throw r.error("max_interval_s", "must be >= min_interval_s");
  if (s.max_force_N < s.min_force_N) throw r.error("max_force_N", "must be >= min_force_N");
  if (s.max_duration_s < s.min_duration_s) throw r.error("max_duration_s", "must be >= min_duration_s");
}

void parse_elasticity(const YamlReader& e, int n, SimRobotConfig::Elasticity& s) {
  e.allow_keys({"enabled", "stiffness_Nm_per_rad", "damping_ratio", "position_loop_encoder", "deflection_filter_s"});
  s.enabled = e.boolean_or("enabled", false);
  if (e.has("stiffness_Nm_per_rad")) s.stiffness_Nm_per_rad = e.per_joint("stiffness_Nm_per_rad", n, 100.0, 1e7);
  s.damping_ratio = e.number_or("damping_ratio", s.damping_ratio, 0.0, 2.0);
  s.deflection_filter_s = e.number_or("deflection_filter_s", s.deflection_filter_s, 0.0, 10.0);
  const std::string encoder = e.choice_or("position_loop_encoder", "motor", {"motor", "motor_compensated", "link"});
  s.position_loop_encoder = encoder == "motor"               ? SimRobotConfig::Elasticity::Encoder::kMotor
                            : encoder == "motor_compensated" ? SimRobotConfig::Elasticity::Encoder::kMotorCompensated
                                                             : SimRobotConfig::Elasticity::Encoder::kLink;
}

SimRobotConfig parse(const YamlReader& root, const std::string& base_dir) {
  root.allow_keys({"plant"});
  const YamlReader p = root.at("plant");
  p.allow_keys({"robot", "drive", "timing", "initial", "seed", "actuator_overrides", "friction_scale", "friction", "noise",
                "ft_sensor", "tool", "mismatch", "vendor", "elasticity", "drop_test", "floor", "disturbances",
                "random_pushes"});
  SimRobotConfig c;
  c.source = root.file();
  parse_robot_files(p.at("robot"), base_dir, c);
  const int n = c.actuators.size();
  c.drive_stated = p.has("drive");
  if (c.drive_stated) c.drive = parse_drive(p.at("drive"), n, c.generic_hold);
  // The vendor section tunes Kinova's loops: under a generic drive it would be silently unused.
  if (c.drive == DriveKind::kGeneric && p.has("vendor")) {
    throw p.error("vendor", "Kinova's drive loops; the plant's drive is generic (its gains: drive.position_hold)");
  }
  if (p.has("timing")) parse_timing(p.at("timing"), c);
  c.initial_q_rad = parse_initial_q(p.at("initial"), n);
  c.seed = static_cast<std::uint64_t>(p.integer_or("seed", 1, 0, (1LL << 62)));
  if (p.has("actuator_overrides")) parse_actuator_overrides(p.at("actuator_overrides"), c);
  c.friction_scale = p.number_or("friction_scale", 1.0, 0.0, 10.0);
  if (p.has("friction")) parse_friction(p.at("friction"), c.friction);
  if (p.has("noise")) parse_noise(p.at("noise"), n, c.noise);
  // The end of arm: an F/T sensor and the tool below it, a tool alone on the flange, or neither (a bare flange).
  if (p.has("ft_sensor") && !p.has("tool")) {
    throw p.error("tool", "the F/T sensor carries a tool: give its section (a bare flange has neither)");
  }
  c.has_end_of_arm = p.has("tool");
  c.has_ft_sensor = p.has("ft_sensor");
  if (c.has_ft_sensor) parse_ft_sensor(p.at("ft_sensor"), c.ft_sensor);
  if (c.has_end_of_arm) parse_tool(p.at("tool"), c.has_ft_sensor, c);
  if (p.has("mismatch")) parse_mismatch(p.at("mismatch"), c.mismatch);
  if (p.has("vendor")) parse_vendor(p.at("vendor"), n, c.vendor);
  if (p.has("elasticity")) parse_elasticity(p.at("elasticity"), n, c.elasticity);
  if (p.has("drop_test")) parse_drop_test(p.at("drop_test"), c.drop_test);
  if (p.has("floor")) parse_floor(p.at("floor"), c.floor);
  if (p.has("disturbances")) c.disturbances = parse_disturbances(p.at("disturbances"));
  if (p.has("random_pushes")) parse_random_pushes(p.at("random_pushes"), c.random_pushes);
  c.fill_defaults();
  c.validate();
  return c;
}

void check_size(const SimRobotConfig& c, const std::vector<double>& v, const std::string& key) {
  if (v.size() != static_cast<std::size_t>(c.dof())) {
    throw ConfigError(c.source, key, "expected " + std::to_string(c.dof()) + " values (one per joint), got " +
                                         std::to_string(v.size()));
  }
}

bool is_integer_ratio(double a, double b) {
  const double r = a / b;
  return std::abs(r - std::round(r)) < 1e-6 && std::round(r) >= 1.0;
}

}  // namespace

SimRobotConfig SimRobotConfig::from_yaml_file(const std::string& path) {
  const std::string base = std::filesystem::path(path).parent_path().string();
  return parse(YamlReader::load_file(path), base);
}

SimRobotConfig SimRobotConfig::from_yaml_string(const std::string& yaml, const std::string& source_name,
                                                const std::string& base_dir) {
  return parse(YamlReader::load_string(yaml, source_name), base_dir);
}

// Defaults of the vendor loops by actuator size (an actuator without `size`: by its maximum torque,
// ActuatorParameters::size_class); see KinovaDriveEmulator and
// robots/kinova_gen3/README.md ("Simulated plant") for why these values.
void SimRobotConfig::fill_defaults() {
  auto& v = vendor;
  const int n = actuators.size();
  auto fill = [&](std::vector<double>& out, double large, double small) {
    if (!out.empty()) return;
    for (int i = 0; i < n; ++i) out.push_back(actuators[i].size_class() == ActuatorSize::kLarge ? large : small);
  };
  fill(v.position_kp_Nm_per_rad, 12000.0, 3000.0);
  fill(v.position_kd_Nms_per_rad, 150.0, 15.0);
  fill(v.position_ki_Nm_per_rad_s, 60000.0, 15000.0);
  fill(v.position_integral_limit_Nm, 60.0, 30.0);
  fill(v.torque_feedback_gain, 0.5, 0.5);
  fill(v.torque_velocity_damping_Nms_per_rad, 15.0, 5.0);
  // Harmonic-drive secant stiffness near 10-20 N.m: CSF-17-100 ~1.3e4 (large), size 14 ~5.5e3 (small);
  // configs/plant_gen3.yaml, plant.elasticity, cites the catalogue values.
  fill(elasticity.stiffness_Nm_per_rad, 13000.0, 5500.0);
  if (noise.torque_sensor_offset_Nm.empty()) noise.torque_sensor_offset_Nm.assign(static_cast<std::size_t>(n), 0.0);
}

int SimRobotConfig::substeps_per_cycle() const {
  return static_cast<int>(std::lround(control_period_s * physics_rate_Hz));
}

namespace {

// The vendor loops: sizes, the torque loop's gain, the integral clamp within the drive's torque,
// and H(z) a stable filter.
void validate_vendor(const SimRobotConfig& c) {
  const std::string& f = c.source;
  const auto& vendor = c.vendor;
  check_size(c, vendor.position_kp_Nm_per_rad, "plant.vendor.position.kp_Nm_per_rad");
  check_size(c, vendor.position_kd_Nms_per_rad, "plant.vendor.position.kd_Nms_per_rad");
  check_size(c, vendor.position_ki_Nm_per_rad_s, "plant.vendor.position.ki_Nm_per_rad_s");
  check_size(c, vendor.position_integral_limit_Nm, "plant.vendor.position.integral_limit_Nm");
  check_size(c, vendor.torque_feedback_gain, "plant.vendor.torque.feedback_gain");
  check_size(c, vendor.torque_velocity_damping_Nms_per_rad, "plant.vendor.torque.velocity_damping_Nms_per_rad");
  for (double g : vendor.torque_feedback_gain) {
    // The torque loop closes through the (almost algebraic) transmission: it needs gain < 1 to be
    // stable with a one-sample measurement delay (see KinovaDriveEmulator).
    if (!(g >= 0.0 && g < 0.95)) throw ConfigError(f, "plant.vendor.torque.feedback_gain", "must be in [0, 0.95)");
  }
  for (int i = 0; i < c.dof(); ++i) {
    // The integral term adds to a torque the motor must produce: no more than the drive can.
    const double limit = vendor.position_integral_limit_Nm[static_cast<std::size_t>(i)];
    const double drive = c.actuators[i].max_motor_torque_Nm();
    if (!(limit <= drive)) {
      throw ConfigError(f, "plant.vendor.position.integral_limit_Nm[" + std::to_string(i) + "]",
                        format_general(limit, 6) + " N.m exceeds " + c.actuators[i].joint_name +
                            "'s drive maximum " + format_general(drive, 6) + " N.m (current_limit_A x K_T x G_r)");
    }
  }
  const auto& num = vendor.high_velocity_numerator;
  const auto& den = vendor.high_velocity_denominator;
  if (num.empty() || den.empty() || num.size() > 6 || den.size() > 6 || den[0] == 0.0) {
    throw ConfigError(f, "plant.vendor.torque_high_velocity", "needs 1..6 numerator and denominator coefficients, a0 != 0");
  }
  for (const double x : num) {
    if (!std::isfinite(x)) throw ConfigError(f, "plant.vendor.torque_high_velocity.numerator", "must be finite");
  }
  const double pole = DiscreteTransferFunction::largest_pole_magnitude(den);
  if (!(pole < 1.0)) {
    throw ConfigError(f, "plant.vendor.torque_high_velocity.denominator",
                      "unstable filter: a pole of magnitude " + format_general(pole, 6) +
                          " (every root of a0 z^n + a1 z^(n-1) + ... + an must lie inside the unit circle)");
  }
}

// A generic drive's gains, one per joint where given; a Kinova drive has none (its vendor section).
void validate_generic_hold(const SimRobotConfig& c) {
  const auto& h = c.generic_hold;
  if (c.drive != DriveKind::kGeneric && !(h.kp_Nm_per_rad.empty() && h.kd_Nms_per_rad.empty())) {
    throw ConfigError(c.source, "drive.position_hold", "a generic drive's gains, and the plant's drive is kinova");
  }
  if (!h.kp_Nm_per_rad.empty()) check_size(c, h.kp_Nm_per_rad, "drive.position_hold.kp_Nm_per_rad");
  if (!h.kd_Nms_per_rad.empty()) check_size(c, h.kd_Nms_per_rad, "drive.position_hold.kd_Nms_per_rad");
  for (std::size_t i = 0; i < h.kp_Nm_per_rad.size(); ++i) {
    const double kp = h.kp_Nm_per_rad[i];
    if (!(kp >= kMinHoldKp_Nm_per_rad && kp <= kMaxHoldKp_Nm_per_rad)) {
      throw ConfigError(c.source, "drive.position_hold.kp_Nm_per_rad[" + std::to_string(i) + "]", "must be in [1, 1e6] N.m/rad");
    }
  }
  for (std::size_t i = 0; i < h.kd_Nms_per_rad.size(); ++i) {
    const double kd = h.kd_Nms_per_rad[i];
    if (!(kd >= 0.0 && kd <= kMaxHoldKd_Nms_per_rad)) {
      throw ConfigError(c.source, "drive.position_hold.kd_Nms_per_rad[" + std::to_string(i) + "]", "must be in [0, 1e4] N.m.s/rad");
    }
  }
}

// The plant's drives after the overrides.
void validate_plant_drives(const SimRobotConfig& c) {
  for (const auto& o : c.actuator_overrides) {
    if (c.actuators.index_of(o.joint) < 0) throw ConfigError(c.source, "plant.actuator_overrides." + o.joint, "unknown joint");
  }
  const ActuatorTable plant = c.plant_actuators();
  for (int i = 0; i < plant.size(); ++i) {
    if (plant[i].reflected_inertia_kgm2 < 1e-3) {
      // The stick-slip friction's presliding stiffness is scaled on it (see StickSlipFriction).
      throw ConfigError(c.source, "plant.actuator_overrides." + plant[i].joint_name + ".reflected_inertia_kgm2",
                        "plant reflected rotor inertia must be >= 1e-3 kg.m^2");
    }
    if (plant[i].friction.static_Nm < plant[i].friction.coulomb_Nm) {
      throw ConfigError(c.source, "plant.actuator_overrides." + plant[i].joint_name + ".static_Nm",
                        "plant static friction must be >= its Coulomb friction");
    }
  }
}

// A configuration built in code names the end of arm's site and gives it mass, as a YAML must.
void validate_end_of_arm(const SimRobotConfig& c) {
  const std::string& f = c.source;
  if (!c.has_end_of_arm) {
    if (c.drop_test.enabled) throw ConfigError(f, "plant.drop_test.enabled", "the drop test hangs its mass from the tool: the plant has no end of arm (ft_sensor, tool)");
    return;
  }
  if (c.ft_sensor.flange_site.empty()) {
    throw ConfigError(f, c.has_ft_sensor ? "plant.ft_sensor.flange_site" : "plant.tool.flange_site", "empty: name the flange's site");
  }
  if (!(c.tool.mass_kg > 0.0)) throw ConfigError(f, "plant.tool.mass_kg", "must be > 0");
  if (!c.has_ft_sensor) return;
  // A mount built in code: a rigid placement within the YAML's reach.
  const Eigen::Isometry3d& mount = c.ft_sensor.sensor_mount;
  if (!mount.matrix().allFinite() || !(mount.translation().norm() <= 0.5) ||
      !(mount.linear().transpose() * mount.linear()).isIdentity(1e-9) || !(mount.linear().determinant() > 0.0)) {
    throw ConfigError(f, "plant.ft_sensor.sensor_xyz_m", "the sensor mount must be a rotation and |xyz| <= 0.5 m");
  }
  if (!(c.ft_sensor.flange_side_mass_kg > 0.0)) throw ConfigError(f, "plant.ft_sensor.flange_side_mass_kg", "must be > 0");
  if (!(c.ft_sensor.flange_side_inertia_kgm2.minCoeff() > 0.0)) {
    throw ConfigError(f, "plant.ft_sensor.flange_side_inertia_kgm2", "principal moments must be > 0");
  }
  if (!(c.tool.inertia_kgm2.minCoeff() > 0.0)) throw ConfigError(f, "plant.tool.inertia_kgm2", "principal moments must be > 0");
}

void validate_scripted_forces(const SimRobotConfig& c) {
  const std::string& f = c.source;
  if (c.drop_test.enabled && !(c.drop_test.cable_length_m > 0.0)) {
    throw ConfigError(f, "plant.drop_test.cable_length_m", "must be positive");
  }
  const auto& r = c.random_pushes;
  if (r.enabled) {
    if (r.max_force_N < r.min_force_N || r.max_interval_s < r.min_interval_s || r.max_duration_s < r.min_duration_s) {
      throw ConfigError(f, "plant.random_pushes", "every max_* must be >= its min_*");
    }
    if (!(r.min_duration_s > 0.0)) throw ConfigError(f, "plant.random_pushes.min_duration_s", "must be positive");
  }
  for (std::size_t i = 0; i < c.disturbances.size(); ++i) {
    const auto& d = c.disturbances[i];
    const std::string key = "plant.disturbances[" + std::to_string(i) + "]";
    if (d.body.empty()) throw ConfigError(f, key + ".body", "empty body name");
    if (!(d.duration_s > 0.0)) throw ConfigError(f, key + ".duration_s", "must be positive");
    if (!d.force_N.allFinite() || !d.torque_Nm.allFinite() || !d.point_m.allFinite()) {
      throw ConfigError(f, key, "values must be finite");
    }
  }
}

}  // namespace

void SimRobotConfig::validate() const {
  const std::string& f = source;
  if (actuators.size() == 0) throw ConfigError(f, "plant.robot.actuators", "no actuators loaded");
  if (!(physics_rate_Hz >= 1000.0) || !is_integer_ratio(physics_rate_Hz, 1000.0)) {
    throw ConfigError(f, "plant.timing.physics_rate_Hz", "must be a multiple of 1000 Hz (the Kortex 1 kHz filter rate)");
  }
  if (!(control_period_s > 0.0) || !is_integer_ratio(control_period_s, physics_step_s())) {
    throw ConfigError(f, "plant.timing.control_period_s", "must be a positive multiple of the physics step");
  }
  if (!(vendor.high_velocity_rate_Hz > 0.0) || !is_integer_ratio(physics_rate_Hz, vendor.high_velocity_rate_Hz)) {
    throw ConfigError(f, "plant.vendor.torque_high_velocity.rate_Hz", "must divide the physics rate");
  }
  if (!(ft_sensor.rate_Hz > 0.0) || !is_integer_ratio(physics_rate_Hz, ft_sensor.rate_Hz)) {
    throw ConfigError(f, "plant.ft_sensor.rate_Hz", "must divide the physics rate");
  }
  if (!gravity_m_s2.allFinite() || !(gravity_m_s2.norm() <= 30.0)) throw ConfigError(f, "gravity_m_s2", "finite, at most 30 m/s^2 (3 g)");
  if (!base_placement.matrix().allFinite()) throw ConfigError(f, "base_placement", "must be finite");
  check_size(*this, initial_q_rad, "plant.initial.q_rad");
  for (std::size_t i = 0; i < initial_q_rad.size(); ++i) {
    if (!(std::abs(initial_q_rad[i]) <= kMaxJointAngle_rad)) {
      throw ConfigError(f, "plant.initial.q_rad[" + std::to_string(i) + "]", "must be within one turn (|q| <= 2 pi)");
    }
  }
  check_size(*this, noise.torque_sensor_offset_Nm, "plant.noise.torque_sensor_offset_Nm");
  if (noise.encoder_counts_per_rev != 0.0 && !(noise.encoder_counts_per_rev >= kMinEncoderCounts)) {
    throw ConfigError(f, "plant.noise.encoder_counts_per_rev", "must be 0 (no quantisation) or >= 4096");
  }
  // Kinova's loops and their keys are checked on a Kinova drive only (a generic drive reads none).
  if (drive == DriveKind::kKinova) {
    actuators.require_stated(actuators_path.empty() ? f : actuators_path, "the plant emulates Kinova's drive loops on the motor data");
    validate_vendor(*this);
  }
  validate_generic_hold(*this);
  check_size(*this, elasticity.stiffness_Nm_per_rad, "plant.elasticity.stiffness_Nm_per_rad");
  validate_plant_drives(*this);
  validate_end_of_arm(*this);
  validate_scripted_forces(*this);
}

ActuatorTable SimRobotConfig::plant_actuators() const {
  ActuatorTable out = actuators;
  for (const auto& o : actuator_overrides) {
    const int i = out.index_of(o.joint);
    if (i < 0) continue;
    ActuatorParameters& a = out[i];
    if (o.coulomb_Nm) a.friction.coulomb_Nm = *o.coulomb_Nm;
    if (o.viscous_Nms_per_rad) a.friction.viscous_Nms_per_rad = *o.viscous_Nms_per_rad;
    if (o.static_Nm) a.friction.static_Nm = *o.static_Nm;
    if (o.reflected_inertia_kgm2) {
      a.reflected_inertia_kgm2 = *o.reflected_inertia_kgm2;
      a.rotor_inertia_kgm2 = a.reflected_inertia_kgm2 / (a.gear_ratio * a.gear_ratio);
    }
    if (o.torque_constant_scale) a.torque_constant_Nm_per_A *= *o.torque_constant_scale;
  }
  if (mismatch.enabled && mismatch.torque_constant_fraction > 0.0) {
    RandomGenerator rng(mismatch.seed, kTorqueConstantMismatchStream);
    for (int i = 0; i < out.size(); ++i) {
      out[i].torque_constant_Nm_per_A *= 1.0 + rng.uniform(-mismatch.torque_constant_fraction, mismatch.torque_constant_fraction);
    }
  }
  for (int i = 0; i < out.size(); ++i) {
    out[i].friction.coulomb_Nm *= friction_scale;
    out[i].friction.viscous_Nms_per_rad *= friction_scale;
    out[i].friction.static_Nm *= friction_scale;
  }
  return out;
}

}  // namespace phri
