#include <phri/config/config.hpp>

#include <phri/config/config_checks.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/config/task_config.hpp>

#include <phri/core/format.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/robot/actuator_table.hpp>

#include <phri/config/physical_ranges.hpp>

#include <cmath>
#include <filesystem>
#include <optional>

namespace phri {
namespace {

constexpr double kHuge = 1e9;

// Physical ranges (the reason next to each; payload and joint-angle bounds in physical_ranges.hpp).
// A payload's COM lies within 1 m of the frame that carries it.
using physical_range::kMaxJointAngle_rad;
using physical_range::kMaxPayload_kg;
using physical_range::kMaxPayloadInertia_kgm2;
// Joint speed: 10 rad/s (~570 deg/s) is beyond any collaborative arm's joint (the Gen3's 2.1 /
// 3.05 rad/s); 120 is deg/s typed as rad/s.
constexpr double kMaxJointVelocity_rad_s = 10.0;
// A torque bound below 0.1 N.m cannot even overcome a joint's friction.
constexpr double kMinTorqueLimit_Nm = 0.1;
// Damping-like gains of the acceleration-level tasks [1/s] (D qd added to qdd each period): with
// D T >= 1 at the 1 kHz period one cycle would more than cancel the velocity. 1000 1/s.
constexpr double kMaxTaskDamping_per_s = 1000.0;

// Input files are made absolute, so that a second resolution (the plant's own loader, against its
// base folder) cannot prefix them again when the configuration was named by a relative path.
constexpr PathForm kInputPaths = PathForm::kAbsolute;

// An input file named under `key`, relative to base_dir; it must exist. Empty text: "" when
// allowed (e.g. no collision model).
std::string input_file(const YamlReader& r, std::string_view key, const std::string& base_dir, bool allow_empty) {
  const std::string text = r.text(key);
  if (text.empty()) {
    if (allow_empty) return "";
    throw r.error(key, "empty file name");
  }
  const std::string path = resolve_path(base_dir, text, kInputPaths);
  if (!std::filesystem::is_regular_file(path)) throw r.error(key, "file not found: " + path);
  return path;
}

// A number > 0 (finite, at most `max`), or the fallback when absent.
double positive_or(const YamlReader& r, std::string_view key, double fallback, double max) {
  if (!r.has(key)) return fallback;
  const double v = r.number(key, 0.0, max);
  if (!(v > 0.0)) throw r.error(key, "must be > 0");
  return v;
}

double non_negative_or(const YamlReader& r, std::string_view key, double fallback, double max) {
  return r.number_or(key, fallback, 0.0, max);
}

// The pairs whose order the controller relies on (a damper's safety distance inside its influence
// distance, a trigger's release level below its press level): an error at `key` otherwise.
void require_below(const YamlReader& r, std::string_view key, double value, double bound, const std::string& reason) {
  if (!(value < bound)) throw r.error(key, reason);
}

ComplianceMode compliance_mode(const YamlReader& r, std::string_view key) {
  return *compliance_mode_from_string(r.choice(key, {"stiff", "null_space", "full_body", "dual"}));
}

// ------------------------------------------------------------------------------------ robot
void parse_robot(const YamlReader& r, const std::string& base_dir, ControllerSettings& c) {
  r.allow_keys({"urdf", "actuators", "collision", "end_effector_frame", "ft_sensor_offset_m", "payloads"});
  c.urdf_path = input_file(r, "urdf", base_dir, false);
  c.actuators_path = input_file(r, "actuators", base_dir, false);
  c.collision_path = r.has("collision") ? input_file(r, "collision", base_dir, true) : "";
  c.end_effector_frame = r.text("end_effector_frame");  // no default: every arm names its own
  // Straight along the end-effector z (a turned or offset mount: a robot bundle's end_of_arm).
  if (r.has("ft_sensor_offset_m")) {
    c.ft_sensor_mount = Eigen::Isometry3d::Identity();
    c.ft_sensor_mount.translation().z() = r.number("ft_sensor_offset_m", 0.0, 0.5);  // an adapter, not a boom
  }
  if (r.has("payloads")) {
    const YamlReader list = r.at("payloads");
    list.expect_sequence();
    c.payloads.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YamlReader p = list.at(i);
      p.allow_keys({"name", "frame", "mass_kg", "com_m", "inertia_kgm2"});
      Payload payload;
      payload.name = p.text("name");
      payload.frame = p.text_or("frame", "");  // empty: the end-effector frame
      payload.inertia.mass = p.number("mass_kg", 0.0, kMaxPayload_kg);
      if (!(payload.inertia.mass > 0.0)) throw p.error("mass_kg", "must be > 0");
      payload.inertia.com = p.vector3_or("com_m", Eigen::Vector3d::Zero(), -1.0, 1.0);
      payload.inertia.inertia_com =
          p.vector3_or("inertia_kgm2", Eigen::Vector3d::Zero(), 0.0, kMaxPayloadInertia_kgm2).asDiagonal();
      c.payloads.push_back(payload);
    }
  }
}

// ------------------------------------------------------------------------------------ plant
// Input files inside a plant `robot:` map, made absolute against the folder of the file naming them.
void absolutize_robot(YAML::Node plant, const std::string& dir) {
  const YAML::Node& view = plant;
  if (!view.IsMap() || !view["robot"] || !view["robot"].IsMap()) return;
  YAML::Node robot = plant["robot"];
  for (const char* key : {"mjcf", "urdf", "actuators"}) {
    const YAML::Node& robot_view = robot;
    if (robot_view[key] && robot_view[key].IsScalar()) {
      robot[key] = resolve_path(dir, robot_view[key].Scalar(), kInputPaths);
    }
  }
}

// Maps merged key by key (recursively); anything else in `over` replaces what `base` has.
void merge(YAML::Node base, const YAML::Node& over) {
  for (const auto& item : over) {
    const std::string key = item.first.as<std::string>();
    const YAML::Node& base_view = base;
    if (item.second.IsMap() && base_view[key] && base_view[key].IsMap()) {
      merge(base[key], item.second);
    } else {
      base[key] = YAML::Clone(item.second);
    }
  }
}

// With a robot bundle, the plant section need not name the arm or its start posture: the bundle's
// files and home posture fill `robot` and `initial` when absent (apply_to then sets its end of arm).
void fill_from_bundle(YAML::Node plant, const RobotBundle& bundle) {
  const YAML::Node& view = plant;
  if (!view["robot"]) {
    YAML::Node robot;
    if (bundle.plant.mjcf_path.empty()) {
      robot["urdf"] = bundle.urdf_path;
    } else {
      robot["mjcf"] = bundle.plant.mjcf_path;
    }
    robot["actuators"] = bundle.actuators_path;
    plant["robot"] = robot;
  }
  if (!view["initial"]) plant["initial"]["q_rad"] = bundle.home_q_rad;
}

SimRobotConfig parse_plant(const YamlReader& r, const std::string& base_dir, const RobotBundle* bundle) {
  r.expect_map();
  const YAML::Node& raw = r.node();
  YAML::Node plant;
  if (r.has("file")) {
    const std::string file = input_file(r, "file", base_dir, false);
    // Through YamlReader: the same syntax checks (duplicate keys, explicit nulls) as every file.
    const YAML::Node loaded = YamlReader::load_file(file).node();
    if (!loaded.IsMap() || !loaded["plant"] || !loaded["plant"].IsMap()) {
      throw ConfigError(file, "plant", "expected a map under the key 'plant'");
    }
    plant = YAML::Clone(loaded["plant"]);
    absolutize_robot(plant, std::filesystem::path(file).parent_path().string());
    YAML::Node overrides = YAML::Clone(raw);
    overrides.remove("file");
    absolutize_robot(overrides, base_dir);
    merge(plant, overrides);
  } else {
    plant = YAML::Clone(raw);
    absolutize_robot(plant, base_dir);
  }
  if (bundle != nullptr) fill_from_bundle(plant, *bundle);
  // A generic drive has no Kinova loops: a vendor section would be silently unused (an error
  // wherever it appears), and the plant is checked under the robot's drive, no Kinova key read.
  if (bundle != nullptr && bundle->drive == DriveKind::kGeneric) {
    if (plant["vendor"]) {
      throw ConfigError(r.file(), "plant.vendor", "Kinova's drive loops; the robot's drive is generic (drive in " + bundle->source +
                                                      "; its hold's gains: drive.position_hold)");
    }
    if (!plant["drive"]) plant["drive"] = "generic";
  }
  YAML::Node document;
  document["plant"] = plant;
  YAML::Emitter out;
  out << document;
  // Key paths in errors stay "plant.<...>", as in this file.
  return SimRobotConfig::from_yaml_string(out.c_str(), r.file(), base_dir);
}

// ------------------------------------------------------------------------------------ controller
void parse_compliance_deadband(const YamlReader& d, int dof, ControllerSettings& c) {
  d.allow_keys({"large_Nm", "small_Nm", "per_joint_Nm"});
  // The dead band hides model error (~1 N.m), not a push: 10 N.m is already a firm push at the wrist.
  c.deadband_large_Nm = non_negative_or(d, "large_Nm", c.deadband_large_Nm, 10.0);
  c.deadband_small_Nm = non_negative_or(d, "small_Nm", c.deadband_small_Nm, 10.0);
  if (d.has("per_joint_Nm")) c.qp.compliance_deadband = d.per_joint<Eigen::VectorXd>("per_joint_Nm", dof, 0.0, 10.0);
}

// The end-effector task's gains, in the stiff and full-body modes.
void parse_end_effector_task(const YamlReader& m, ComplianceSettings& s) {
  s.ee_position_stiffness = non_negative_or(m, "ee_position_stiffness", s.ee_position_stiffness, 1e5);
  s.ee_orientation_stiffness = non_negative_or(m, "ee_orientation_stiffness", s.ee_orientation_stiffness, 1e5);
  s.ee_weight = non_negative_or(m, "ee_weight", s.ee_weight, 1e9);
  s.full_body_ee_stiffness = non_negative_or(m, "full_body_ee_stiffness", s.full_body_ee_stiffness, 1e5);
}

void parse_posture_task(const YamlReader& m, ComplianceSettings& s) {
  s.posture_stiffness = non_negative_or(m, "posture_stiffness", s.posture_stiffness, 1e5);
  s.posture_damping = non_negative_or(m, "posture_damping", s.posture_damping, kMaxTaskDamping_per_s);
  s.posture_weight = positive_or(m, "posture_weight", s.posture_weight, 1e9);
}

// Dual compliance: the Schmitt trigger on the filtered wrench and the damping while touched.
void parse_touch_trigger(const YamlReader& m, ControllerSettings& c) {
  ComplianceSettings& s = c.compliance;
  // Wrench levels of a hand: 1000 N (or N.m) is far beyond any touch (the demo's 8 / 4).
  s.touch_threshold = non_negative_or(m, "touch_threshold", s.touch_threshold, 1e3);
  s.release_threshold = non_negative_or(m, "release_threshold", s.release_threshold, 1e3);
  s.touched_ee_damping = non_negative_or(m, "touched_ee_damping", s.touched_ee_damping, kMaxTaskDamping_per_s);
  s.touched_posture_damping = non_negative_or(m, "touched_posture_damping", s.touched_posture_damping, kMaxTaskDamping_per_s);
  c.wrench_trigger_filter_s = non_negative_or(m, "trigger_filter_s", c.wrench_trigger_filter_s, 1.0);
  require_below(m, "release_threshold", s.release_threshold, s.touch_threshold,
                "must be below touch_threshold (the Schmitt trigger's hysteresis)");
}

void parse_compliance(const YamlReader& m, ControllerSettings& c) {
  m.allow_keys({"initial_mode", "ee_position_stiffness", "ee_orientation_stiffness", "ee_weight",
                "full_body_ee_stiffness", "posture_stiffness", "posture_damping", "posture_weight", "touch_threshold",
                "release_threshold", "touched_ee_damping", "touched_posture_damping", "trigger_filter_s"});
  if (m.has("initial_mode")) c.initial_compliance = compliance_mode(m, "initial_mode");
  parse_end_effector_task(m, c.compliance);
  parse_posture_task(m, c.compliance);
  parse_touch_trigger(m, c);
}

// qp.joint_limits: the joint-limit velocity damper.
void parse_joint_limit_damper(const YamlReader& j, WholeBodyQpSettings& s) {
  j.allow_keys({"influence_fraction", "safety_fraction", "amortization"});
  s.joint_influence_fraction = positive_or(j, "influence_fraction", s.joint_influence_fraction, 0.49);
  s.joint_safety_fraction = non_negative_or(j, "safety_fraction", s.joint_safety_fraction, 0.49);
  s.joint_damper_amortization = j.number_or("amortization", s.joint_damper_amortization, 1.0, 100.0);
  require_below(j, "safety_fraction", s.joint_safety_fraction, s.joint_influence_fraction,
                "must be below influence_fraction (d_s < d_i)");
}

// qp.collision: the self-collision velocity damper.
void parse_collision_damper(const YamlReader& k, VelocityDamperSettings& d) {
  k.allow_keys({"influence_distance_m", "safety_distance_m", "approach_speed_m_s", "amortization"});
  d.influence_distance = positive_or(k, "influence_distance_m", d.influence_distance, 1.0);
  // 0 would let capsules touch before the damper stops their approach.
  d.safety_distance = positive_or(k, "safety_distance_m", d.safety_distance, 1.0);
  d.xi = positive_or(k, "approach_speed_m_s", d.xi, 10.0);
  d.amortization = k.number_or("amortization", d.amortization, 1.0, 100.0);
  require_below(k, "safety_distance_m", d.safety_distance, d.influence_distance,
                "must be below influence_distance_m (d_s < d_i)");
}

// qp.torque_limit_Nm overrides actuators.yaml's bounds: each within what its drive can produce.
Eigen::VectorXd parse_torque_limits(const YamlReader& q, const ActuatorTable& drives) {
  const Eigen::VectorXd limits = q.per_joint<Eigen::VectorXd>("torque_limit_Nm", drives.size(), kMinTorqueLimit_Nm, 1e5);
  for (int i = 0; i < drives.size(); ++i) {
    if (limits[i] > drives[i].max_motor_torque_Nm() * (1.0 + 1e-9)) {
      throw q.error("torque_limit_Nm[" + std::to_string(i) + "]",
                    format_general(limits[i], 6) + " N.m exceeds " + drives[i].joint_name + "'s drive maximum " +
                        format_general(drives[i].max_motor_torque_Nm(), 6) + " N.m (actuators.yaml: current_limit_A x K_T x G_r)");
    }
  }
  return limits;
}

// A body region of a regions file (configs/iso_ts_15066_regions.yaml's form), by name; an unknown
// name is an error at `key` of `at`.
BodyRegion load_body_region(const std::string& file, const std::string& name, const YamlReader& at, std::string_view key) {
  const YamlReader root = YamlReader::load_file(file);
  root.allow_keys({"regions"});
  const YamlReader list = root.at("regions");
  list.expect_sequence();
  std::string known;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader r = list.at(i);
    r.allow_keys({"name", "stiffness_N_per_mm", "mass_kg", "quasi_static_force_N", "transient_factor"});
    const std::string region_name = r.text("name");
    known += (known.empty() ? "" : ", ") + region_name;
    if (region_name != name) continue;
    BodyRegion region;
    region.name = region_name;
    region.stiffness_N_per_m = 1e3 * r.number("stiffness_N_per_mm", 0.1, 1e4);
    region.mass_kg = r.number("mass_kg", 0.01, 1000.0);
    region.quasi_static_force_N = r.number("quasi_static_force_N", 1.0, 1e4);
    region.transient_factor = r.number_or("transient_factor", 2.0, 1.0, 10.0);
    return region;
  }
  throw at.error(key, "no region '" + name + "' in " + file + " (" + known + ")");
}

// {regions_file, region, links: {link: region}}: the region any link may meet and the named
// links' own (control/power_force_limit.hpp, BodyRegionMap); `keys`: the block's allowed keys.
BodyRegionMap parse_body_regions(const YamlReader& p, const std::string& base_dir, std::initializer_list<std::string_view> keys) {
  p.allow_keys(keys);
  const std::string file = input_file(p, "regions_file", base_dir, false);
  BodyRegionMap map;
  map.region = load_body_region(file, p.text("region"), p, "region");
  if (p.has("links")) {
    const YamlReader links = p.at("links");
    links.expect_map();
    for (const std::string& link : links.keys()) map.links.emplace_back(link, load_body_region(file, links.text(link), links, link));
  }
  return map;
}

// controller.qp.power_force_limit: {regions_file, region, links, gain} (control/power_force_limit.hpp).
PowerForceLimitSettings parse_power_force_limit(const YamlReader& p, const std::string& base_dir) {
  PowerForceLimitSettings s;
  s.regions = parse_body_regions(p, base_dir, {"regions_file", "region", "links", "gain"});
  s.gain = p.number_or("gain", s.gain, 1.0, 1e3);
  return s;
}

void parse_qp(const YamlReader& q, const ActuatorTable& drives, const std::string& base_dir, WholeBodyQpSettings& s) {
  q.allow_keys({"torque_limit_Nm", "velocity_limit_rad_s", "velocity_limit_fraction", "joint_limits",
                "velocity_limit_gain", "braking_reserve", "collision", "collision_braking", "regularization", "brake_damping",
                "smoothing_time_constant_s", "singular_value_threshold", "power_force_limit"});
  if (q.has("power_force_limit")) s.power_force_limit = parse_power_force_limit(q.at("power_force_limit"), base_dir);
  const int dof = drives.size();
  if (q.has("torque_limit_Nm")) s.torque_limit = parse_torque_limits(q, drives);
  if (q.has("velocity_limit_rad_s")) {
    s.velocity_limit = q.per_joint<Eigen::VectorXd>("velocity_limit_rad_s", dof, 1e-3, kMaxJointVelocity_rad_s);
  }
  // Below 5 % of the joints' speed limits the arm can neither yield to a hand nor follow a reference.
  s.velocity_limit_fraction = q.number_or("velocity_limit_fraction", s.velocity_limit_fraction, 0.05, 1.0);
  if (q.has("joint_limits")) parse_joint_limit_damper(q.at("joint_limits"), s);
  s.velocity_limit_gain = positive_or(q, "velocity_limit_gain", s.velocity_limit_gain, kMaxTaskDamping_per_s);
  if (q.has("braking_reserve")) {
    const YamlReader b = q.at("braking_reserve");
    b.allow_keys({"reserve_fraction", "min_speed_fraction", "return_gain"});
    s.braking_reserve.reserve_fraction = b.number_or("reserve_fraction", s.braking_reserve.reserve_fraction, 0.0, 1.0);
    s.braking_reserve.min_speed_fraction = b.number_or("min_speed_fraction", s.braking_reserve.min_speed_fraction, 0.05, 1.0);
    s.braking_reserve.return_gain = b.number_or("return_gain", s.braking_reserve.return_gain, 0.0, kMaxTaskDamping_per_s);
  }
  if (q.has("collision")) parse_collision_damper(q.at("collision"), s.collision);
  if (q.has("collision_braking")) {
    const YamlReader b = q.at("collision_braking");
    b.allow_keys({"deceleration_m_s2", "gain_per_s"});
    s.collision_braking.deceleration = b.number_or("deceleration_m_s2", s.collision_braking.deceleration, 0.0, 100.0);
    s.collision_braking.gain = positive_or(b, "gain_per_s", s.collision_braking.gain, kMaxTaskDamping_per_s);
  }
  s.regularization = non_negative_or(q, "regularization", s.regularization, 1.0);
  s.singular_value_threshold = non_negative_or(q, "singular_value_threshold", s.singular_value_threshold, 0.5);
  s.brake_damping = positive_or(q, "brake_damping", s.brake_damping, kMaxTaskDamping_per_s);
  s.smoothing_time_constant = non_negative_or(q, "smoothing_time_constant_s", s.smoothing_time_constant, 10.0);
}

void parse_wrench(const YamlReader& w, WrenchEstimatorSettings& s) {
  w.allow_keys({"tool_mass_kg", "tool_com_m", "bias_samples"});
  s.tool_mass_kg = non_negative_or(w, "tool_mass_kg", s.tool_mass_kg, kMaxPayload_kg);
  s.tool_com_m = w.vector3_or("tool_com_m", s.tool_com_m, -1.0, 1.0);
  // 0 would estimate no bias: the sensor's offset would stay in the wrench (a touch that is not there).
  s.bias_samples = static_cast<int>(w.integer_or("bias_samples", s.bias_samples, 1, 1000000));
}

void parse_controller(const YamlReader& r, const ActuatorTable& drives, const std::string& base_dir, ControllerSettings& c) {
  r.allow_keys({"period_s", "observer_gain", "external_torque_source", "position_mode_open_loop", "compliance_deadband",
                "compliance", "qp", "wrench", "tasks", "constraints"});
  c.position_mode_open_loop = r.boolean_or("position_mode_open_loop", c.position_mode_open_loop);
  c.period_s = positive_or(r, "period_s", c.period_s, 0.1);
  if (r.has("external_torque_source")) {
    c.external_torque_source = *external_torque_source_from_string(r.choice("external_torque_source", {"observer", "ft", "fused"}));
  }
  c.observer_gain = positive_or(r, "observer_gain", c.observer_gain, 1e4);
  // The discrete observer's residual follows r[k] = (1 - K T) r[k-1] + K T tau_ext[k]: it rings
  // for K T > 1 and diverges for K T > 2. K T < 1 keeps it a first-order low-pass.
  if (!(c.observer_gain * c.period_s < 1.0)) {
    throw r.error("observer_gain", "observer_gain x period_s must be < 1 (the discrete observer rings above 1 and "
                                   "diverges above 2), got " + format_general(c.observer_gain, 6) + " x " +
                                       format_general(c.period_s, 6) + " = " +
                                       format_general(c.observer_gain * c.period_s, 6));
  }
  if (r.has("compliance_deadband")) parse_compliance_deadband(r.at("compliance_deadband"), drives.size(), c);
  if (r.has("compliance")) parse_compliance(r.at("compliance"), c);
  if (r.has("qp")) parse_qp(r.at("qp"), drives, base_dir, c.qp);
  if (r.has("wrench")) parse_wrench(r.at("wrench"), c.wrench);
  if (r.has("tasks")) c.tasks = parse_task_specs(r.at("tasks"));
  if (r.has("constraints")) c.constraints = parse_constraint_specs(r.at("constraints"));
}

// ------------------------------------------------------------------------------------ low level
void parse_low_level(const YamlReader& r, ControllerSettings& c, FsmSettings& fsm) {
  r.allow_keys({"torque_loop", "custom"});
  if (r.has("torque_loop")) {
    fsm.torque_loop = *low_level_mode_from_string(
        r.choice("torque_loop", {"kinova_torque", "kinova_torque_high_velocity", "custom", "torque"}));
    if (!c.offered_loops.contains(fsm.torque_loop)) {
      throw r.error("torque_loop", "'" + std::string(to_string(fsm.torque_loop)) + "' is not a loop the robot's drives offer (" +
                                       c.offered_loops.names() + ")");
    }
  }
  if (r.has("custom")) {
    const YamlReader k = r.at("custom");
    k.allow_keys({"transfer_gain", "integral_gain", "integral_leak", "integral_limit_fraction",
                  "friction_compensation", "rotor_inertia_compensation"});
    CustomTorqueSettings& s = c.custom_torque;
    // lambda on H(z): 50 is 10x the paper's 5; K_I and theta at most 1000 1/s, the control rate
    // (an integrator that leaks or acts faster than one period is no integrator).
    s.transfer_gain = non_negative_or(k, "transfer_gain", s.transfer_gain, 50.0);
    s.integral_gain = non_negative_or(k, "integral_gain", s.integral_gain, 1e3);
    s.integral_leak = non_negative_or(k, "integral_leak", s.integral_leak, 1e3);
    s.integral_limit_fraction = non_negative_or(k, "integral_limit_fraction", s.integral_limit_fraction, 1.0);
    s.friction_compensation = k.boolean_or("friction_compensation", s.friction_compensation);
    s.rotor_inertia_compensation = k.boolean_or("rotor_inertia_compensation", s.rotor_inertia_compensation);
  }
}

// ------------------------------------------------------------------------------------ fsm
void parse_fsm(const YamlReader& r, int dof, FsmSettings& f) {
  r.allow_keys({"first_scenario", "stiffness_step", "rest_speed_rad_s", "startup", "static", "dynamic", "brake"});
  if (r.has("first_scenario")) {
    f.first_scenario = r.choice("first_scenario", {"static", "dynamic"}) == "static" ? Scenario::kStatic
                                                                                   : Scenario::kDynamic;
  }
  f.stiffness_step = r.number_or("stiffness_step", f.stiffness_step, 1.0, 10.0);
  f.rest_speed_rad_s = positive_or(r, "rest_speed_rad_s", f.rest_speed_rad_s, 0.5);  // "at rest": well below motion
  if (r.has("startup")) {
    const YamlReader s = r.at("startup");
    s.allow_keys({"enabled", "home_q_rad", "max_joint_speed_rad_s", "min_duration_s", "tolerance_rad", "timeout_s"});
    StartupSettings& st = f.startup;
    st.enabled = s.boolean_or("enabled", st.enabled);
    if (s.has("home_q_rad")) st.home_q_rad = s.per_joint("home_q_rad", dof, -kMaxJointAngle_rad, kMaxJointAngle_rad);
    st.max_joint_speed_rad_s = positive_or(s, "max_joint_speed_rad_s", st.max_joint_speed_rad_s, 5.0);
    st.min_duration_s = non_negative_or(s, "min_duration_s", st.min_duration_s, 1000.0);
    st.tolerance_rad = positive_or(s, "tolerance_rad", st.tolerance_rad, 1.0);  // a posture error norm, not a turn
    st.timeout_s = non_negative_or(s, "timeout_s", st.timeout_s, 1000.0);
  }
  if (r.has("static")) {
    const YamlReader s = r.at("static");
    s.allow_keys({"posture_q_rad", "move_speed_m_s", "move_angular_speed_rad_s", "move_joint_speed_rad_s",
                  "min_move_duration_s"});
    StaticScenarioSettings& st = f.static_scenario;
    if (s.has("posture_q_rad")) {
      st.posture_q_rad = s.per_joint("posture_q_rad", dof, -kMaxJointAngle_rad, kMaxJointAngle_rad);
    }
    st.move_speed_m_s = positive_or(s, "move_speed_m_s", st.move_speed_m_s, 2.0);
    st.move_angular_speed_rad_s = positive_or(s, "move_angular_speed_rad_s", st.move_angular_speed_rad_s, 10.0);
    st.move_joint_speed_rad_s = positive_or(s, "move_joint_speed_rad_s", st.move_joint_speed_rad_s, 2.0);
    st.min_move_duration_s = non_negative_or(s, "min_move_duration_s", st.min_move_duration_s, 1000.0);
  }
  if (r.has("dynamic")) {
    const YamlReader d = r.at("dynamic");
    d.allow_keys({"vertical_amplitude_m", "vertical_angular_frequency_rad_s", "horizontal_speed_m_s",
                  "horizontal_min_offset_m", "horizontal_max_offset_m", "horizontal_turn_acceleration_m_s2", "ramp_s",
                  "compliance"});
    DynamicScenarioSettings& dy = f.dynamic_scenario;
    dy.vertical_amplitude_m = non_negative_or(d, "vertical_amplitude_m", dy.vertical_amplitude_m, 1.0);
    dy.vertical_angular_frequency_rad_s =
        non_negative_or(d, "vertical_angular_frequency_rad_s", dy.vertical_angular_frequency_rad_s, 100.0);
    dy.horizontal_speed_m_s = non_negative_or(d, "horizontal_speed_m_s", dy.horizontal_speed_m_s, 2.0);
    dy.horizontal_min_offset_m = d.number_or("horizontal_min_offset_m", dy.horizontal_min_offset_m, -2.0, 0.0);
    dy.horizontal_max_offset_m = d.number_or("horizontal_max_offset_m", dy.horizontal_max_offset_m, 0.0, 2.0);
    dy.horizontal_turn_acceleration_m_s2 =
        positive_or(d, "horizontal_turn_acceleration_m_s2", dy.horizontal_turn_acceleration_m_s2, 100.0);
    dy.ramp_s = non_negative_or(d, "ramp_s", dy.ramp_s, 100.0);
    if (d.has("compliance")) {
      const std::string mode = d.choice("compliance", {"keep", "stiff", "null_space", "full_body", "dual"});
      dy.compliance = mode == "keep" ? std::nullopt : compliance_mode_from_string(mode);
    }
    const double span = dy.horizontal_max_offset_m - dy.horizontal_min_offset_m;
    if (dy.horizontal_speed_m_s * dy.horizontal_speed_m_s > dy.horizontal_turn_acceleration_m_s2 * span + 1e-12) {
      throw d.error("horizontal_speed_m_s",
                    "too fast for the span: the two turns need speed^2 / horizontal_turn_acceleration_m_s2 <= "
                    "horizontal_max_offset_m - horizontal_min_offset_m");
    }
  }
  if (r.has("brake")) {
    const YamlReader b = r.at("brake");
    b.allow_keys({"linear_deceleration_m_s2", "angular_deceleration_rad_s2", "joint_deceleration_rad_s2",
                  "min_duration_s"});
    BrakeSettings& br = f.brake;
    br.linear_deceleration_m_s2 = positive_or(b, "linear_deceleration_m_s2", br.linear_deceleration_m_s2, 100.0);
    br.angular_deceleration_rad_s2 = positive_or(b, "angular_deceleration_rad_s2", br.angular_deceleration_rad_s2, 100.0);
    br.joint_deceleration_rad_s2 = positive_or(b, "joint_deceleration_rad_s2", br.joint_deceleration_rad_s2, 100.0);
    br.min_duration_s = positive_or(b, "min_duration_s", br.min_duration_s, 10.0);
  }
}

std::vector<TimedEvent> parse_events(const YamlReader& list, double duration_s, const LowLevelModeSet& offered_loops) {
  list.expect_sequence();
  std::vector<TimedEvent> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader e = list.at(i);
    e.allow_keys({"at", "event"});
    TimedEvent timed;
    timed.time_s = e.number("at", 0.0, kHuge);
    // An event after the end of the run is most likely a typo in `at` or in run.duration_s.
    if (timed.time_s > duration_s) throw e.error("at", "after the end of the run (run.duration_s)");
    const std::string name = e.text("event");
    const auto event = event_from_string(name);
    if (!event) {
      std::string names;
      for (std::string_view n : kEventNames) names += (names.empty() ? "" : ", ") + std::string(n);
      throw e.error("event", "unknown event '" + name + "' (one of " + names + ")");
    }
    const std::optional<LowLevelMode> loop = loop_of(*event);
    if (loop && !offered_loops.contains(*loop)) {
      throw e.error("event", "'" + std::string(to_string(*loop)) + "' is not a loop the robot's drives offer (" +
                                 offered_loops.names() + ")");
    }
    timed.event = *event;
    out.push_back(timed);
  }
  std::stable_sort(out.begin(), out.end(), [](const TimedEvent& a, const TimedEvent& b) { return a.time_s < b.time_s; });
  return out;
}

// ------------------------------------------------------------------------------------ logging, gamepad, run
void parse_logging(const YamlReader& l, Config& c) {
  l.allow_keys({"enabled", "path", "buffer_rows", "legend", "format", "ros_topics_every"});
  c.logging_enabled = l.boolean_or("enabled", c.logging_enabled);
  c.logging.path = l.text_or("path", c.logging.path);
  if (c.logging.path.empty()) throw l.error("path", "empty file name");
  const std::string format = l.text_or("format", "auto");
  if (format != "auto" && format != "csv" && format != "mcap") throw l.error("format", "auto, csv or mcap, got '" + format + "'");
  c.log_format_auto = format == "auto";
  if (!c.log_format_auto) c.logging.format = format == "mcap" ? LogFormat::kMcap : LogFormat::kCsv;
  c.logging.ros_topics_every = static_cast<int>(l.integer_or("ros_topics_every", c.logging.ros_topics_every, 1, 1000));
  const long long rows = l.integer_or("buffer_rows", static_cast<long long>(c.logging.capacity_rows), 16, 1LL << 40);
  if (rows > static_cast<long long>(log_ring_max_rows())) {
    throw l.error("buffer_rows", "at most " + std::to_string(log_ring_max_rows()) + " rows of " +
                                     std::to_string(sizeof(LogRow)) + " bytes (the log ring stays under 100 MiB), got " +
                                     std::to_string(rows));
  }
  c.logging.capacity_rows = static_cast<std::size_t>(rows);
  c.logging.write_legend = l.boolean_or("legend", c.logging.write_legend);
}

void parse_gamepad(const YamlReader& g, GamepadSettings& s) {
  g.allow_keys({"enabled", "poll_interval_ms", "trigger_press", "trigger_release"});
  s.enabled = g.boolean_or("enabled", s.enabled);
  s.poll_interval_ms = static_cast<int>(g.integer_or("poll_interval_ms", s.poll_interval_ms, 1, 1000));
  GamepadMapping& m = s.mapping;
  m.trigger_press = positive_or(g, "trigger_press", m.trigger_press, 1.0);
  m.trigger_release = non_negative_or(g, "trigger_release", m.trigger_release, 1.0);
  require_below(g, "trigger_release", m.trigger_release, m.trigger_press, "must be below trigger_press");
}

void parse_run(const YamlReader& r, RunSettings& s) {
  r.allow_keys({"duration_s", "pacing"});
  s.duration_s = positive_or(r, "duration_s", s.duration_s, kHuge);
  if (s.duration_s > RunSettings::kMaxDuration_s) {
    throw r.error("duration_s", "at most 3600 s (the run keeps one cycle time per period), got " +
                                    format_general(s.duration_s, 10));
  }
  if (r.has("pacing")) {
    s.pacing = r.choice("pacing", {"real_time", "lockstep"}) == "real_time" ? LoopPacing::kRealTime
                                                                 : LoopPacing::kLockstep;
  }
}

void parse_ros2(const YamlReader& r, Ros2Settings& s) {
  r.allow_keys({"enabled", "domain", "namespace", "joint_states_decimation", "decimation", "subscribe",
                "max_input_rate_hz", "max_reach_m", "discovery", "ft_in"});
  s.enabled = r.boolean_or("enabled", s.enabled);
  s.domain = static_cast<int>(r.integer_or("domain", s.domain, -1, 232));
  s.topic_namespace = r.text_or("namespace", s.topic_namespace);
  if (!valid_ros_namespace(s.topic_namespace)) {
    throw r.error("namespace", "a ROS 2 namespace such as /phri ('/' then [A-Za-z0-9_] segments), got '" + s.topic_namespace + "'");
  }
  s.joint_states_decimation = static_cast<int>(r.integer_or("joint_states_decimation", s.joint_states_decimation, 1, 100000));
  s.decimation = static_cast<int>(r.integer_or("decimation", s.decimation, 1, 100000));
  s.subscribe = r.boolean_or("subscribe", s.subscribe);
  s.ft_in = r.boolean_or("ft_in", s.ft_in);
  s.max_input_rate_hz = positive_or(r, "max_input_rate_hz", s.max_input_rate_hz, 1000.0);
  s.max_reach_m = non_negative_or(r, "max_reach_m", s.max_reach_m, 10.0);
  if (r.has("discovery")) s.discovery = r.choice("discovery", {"loopback", "network"});
}

// The robot: a bundle's folder (a scalar, or `robot_folder` from the command line), or the map of files.
std::optional<RobotBundle> parse_robot_section(const YamlReader& root, const std::string& base_dir,
                                               const std::string& robot_folder, ControllerSettings& c) {
  std::optional<RobotBundle> bundle;
  if (!robot_folder.empty()) {
    bundle = RobotBundle::from_folder(robot_folder);
  } else {
    const YamlReader robot = root.at("robot");
    if (!robot.node().IsScalar()) {
      parse_robot(robot, base_dir, c);
      return bundle;
    }
    std::string folder = resolve_path(base_dir, robot.as_text(), kInputPaths);
    if (std::filesystem::path(folder).filename() == "robot.yaml") folder = std::filesystem::path(folder).parent_path().string();
    if (!std::filesystem::is_regular_file(std::filesystem::path(folder) / "robot.yaml")) {
      throw robot.error("", "no robot.yaml in the robot folder " + folder);
    }
    bundle = RobotBundle::from_folder(folder);
  }
  bundle->apply_to(c);
  return bundle;
}

Config parse(const YamlReader& root, const std::string& base_dir, const std::string& robot_folder = "") {
  const std::string& source = root.file();
  root.allow_keys({"robot", "plant", "controller", "low_level", "fsm", "events", "logging", "gamepad", "run", "ros2",
                   "body_regions"});
  Config c;
  c.source = source;

  const std::optional<RobotBundle> bundle = parse_robot_section(root, base_dir, robot_folder, c.controller);
  const ActuatorTable drives = ActuatorTable::from_yaml_file(c.controller.actuators_path);
  const int dof = drives.size();

  if (bundle && !root.has("plant")) {
    c.plant.source = source;
  } else {
    c.plant = parse_plant(root.at("plant"), base_dir, bundle ? &*bundle : nullptr);
  }
  if (bundle) bundle->apply_to(c.plant);
  c.robot_name = bundle ? bundle->name : std::filesystem::path(c.controller.urdf_path).stem().string();
  // Without a bundle, a plant that names its drives decides the loops the controller may ask for.
  if (!bundle && c.plant.drive_stated) c.controller.offered_loops = offered_loops(c.plant.drive);
  if (c.plant.dof() != dof) {
    throw ConfigError(source, "plant.robot.actuators",
                      "the plant has " + std::to_string(c.plant.dof()) + " joints, the controller's robot.actuators " +
                          std::to_string(dof));
  }

  if (root.has("controller")) parse_controller(root.at("controller"), drives, base_dir, c.controller);
  if (!c.plant.ft_sensor_present() && c.controller.external_torque_source != ExternalTorqueSource::kObserver) {
    throw ConfigError(source, "controller.external_torque_source",
                      std::string(to_string(c.controller.external_torque_source)) + " needs an F/T sensor, and the plant has none (" +
                          (c.plant.has_end_of_arm ? "a tool without a sensor" : "no end of arm") + ")");
  }
  if (std::abs(c.controller.period_s - c.plant.control_period_s) > 1e-12) {
    throw ConfigError(source, "controller.period_s",
                      "must equal the plant's control period (plant.timing.control_period_s)");
  }
  if (root.has("low_level")) parse_low_level(root.at("low_level"), c.controller, c.fsm);
  if (bundle) {  // the FSM's postures default to the robot's home (the library's are the Gen3's)
    c.fsm.startup.home_q_rad = bundle->home_q_rad;
    c.fsm.static_scenario.posture_q_rad = bundle->home_q_rad;
  }
  if (root.has("fsm")) parse_fsm(root.at("fsm"), dof, c.fsm);
  // The FSM's start-up runs in Position; without it the run starts in the torque loop.
  c.controller.initial_loop = c.fsm.startup.enabled ? LowLevelMode::kPosition : c.fsm.torque_loop;

  if (root.has("logging")) parse_logging(root.at("logging"), c);
  c.logging.dof = std::min(dof, kLogMaxJoints);
  if (root.has("gamepad")) parse_gamepad(root.at("gamepad"), c.gamepad);
  if (root.has("run")) parse_run(root.at("run"), c.run);
  if (root.has("ros2")) parse_ros2(root.at("ros2"), c.ros2);
  if (root.has("body_regions")) {
    c.body_regions = parse_body_regions(root.at("body_regions"), base_dir, {"regions_file", "region", "links"});
  } else if (c.controller.qp.power_force_limit) {
    c.body_regions = c.controller.qp.power_force_limit->regions;
  }
  if (root.has("events")) c.fsm.timeline = parse_events(root.at("events"), c.run.duration_s, c.controller.offered_loops);
  check_config_against_robot(c);
  return c;
}

}  // namespace

LogFormat resolve_log_format(Config& config) {
  std::filesystem::path path(config.logging.path);
  if (config.log_format_auto) {
    const bool long_run = config.run.duration_s > kCsvLogMaxAutoDurationS;
    config.logging.format = path.extension() == ".mcap" || long_run ? LogFormat::kMcap : LogFormat::kCsv;
    config.log_format_auto = false;
  }
  if (path.extension() == ".csv" || path.extension() == ".mcap") {
    path.replace_extension(config.logging.format == LogFormat::kMcap ? ".mcap" : ".csv");
    config.logging.path = path.string();
  }
  return config.logging.format;
}

BodyRegion body_region_from_file(const std::string& file, const std::string& name) {
  return load_body_region(file, name, YamlReader::load_file(file), "regions");
}

Config Config::from_yaml_file(const std::string& path) {
  return parse(YamlReader::load_file(path), std::filesystem::path(path).parent_path().string());
}

Config Config::from_yaml_file(const std::string& path, const std::string& robot_folder) {
  return parse(YamlReader::load_file(path), std::filesystem::path(path).parent_path().string(), robot_folder);
}

Config Config::from_yaml_string(const std::string& yaml, const std::string& source_name, const std::string& base_dir) {
  return parse(YamlReader::load_string(yaml, source_name), base_dir);
}

}  // namespace phri
