#include <phri/core/random_generator.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/sim/sim_robot_config.hpp>

#include <cmath>
#include <filesystem>

namespace phri {
namespace {

// Random stream of the drive-gain mismatch (SimRobot uses stream 3 of the same seed for the links).
constexpr std::uint64_t kTorqueConstantMismatchStream = 4;

constexpr double kHuge = 1e9;

std::string resolve(const std::string& base_dir, const std::string& file) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || base_dir.empty()) return p.lexically_normal().string();
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

Eigen::Vector3d vector3(const YamlReader& r, std::string_view key, double min, double max) {
  const auto v = r.numbers(key, 3, min, max);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Vector3d vector3_or(const YamlReader& r, std::string_view key, const Eigen::Vector3d& fallback, double min,
                           double max) {
  return r.has(key) ? vector3(r, key, min, max) : fallback;
}

ExternalForce::Profile parse_profile(const std::string& name) {
  if (name == "step") return ExternalForce::Profile::kStep;
  if (name == "ramp") return ExternalForce::Profile::kRamp;
  return ExternalForce::Profile::kHalfSine;
}

std::vector<double> per_joint(const YamlReader& r, std::string_view key, int n, double min, double max) {
  return r.numbers(key, n, min, max);
}

SimRobotConfig parse(const YamlReader& root, const std::string& base_dir) {
  root.allow_keys({"plant"});
  const YamlReader p = root.at("plant");
  p.allow_keys({"robot", "timing", "initial", "seed", "actuator_overrides", "friction_scale", "friction", "noise",
                "ft_sensor", "tool", "mismatch", "vendor", "drop_test", "floor", "disturbances", "random_pushes"});
  SimRobotConfig c;
  c.source = root.file();

  const YamlReader robot = p.at("robot");
  robot.allow_keys({"mjcf", "actuators"});
  c.mjcf_path = resolve(base_dir, robot.text("mjcf"));
  c.actuators_path = resolve(base_dir, robot.text("actuators"));
  c.actuators = ActuatorTable::from_yaml_file(c.actuators_path);
  const int n = c.actuators.size();

  if (p.has("timing")) {
    const YamlReader t = p.at("timing");
    t.allow_keys({"physics_rate_Hz", "control_period_s"});
    c.physics_rate_Hz = t.number_or("physics_rate_Hz", c.physics_rate_Hz, 1000.0, 100000.0);
    c.control_period_s = t.number_or("control_period_s", c.control_period_s, 1e-4, 0.1);
  }

  const YamlReader init = p.at("initial");
  init.allow_keys({"q_rad"});
  c.initial_q_rad = per_joint(init, "q_rad", n, -100.0, 100.0);

  c.seed = static_cast<std::uint64_t>(p.integer_or("seed", 1, 0, (1LL << 62)));

  if (p.has("actuator_overrides")) {
    const YamlReader o = p.at("actuator_overrides");
    o.expect_map();
    for (const auto& a : c.actuators.joints()) {
      if (!o.has(a.joint_name)) continue;
      const YamlReader j = o.at(a.joint_name);
      j.allow_keys({"coulomb_Nm", "viscous_Nms_per_rad", "static_Nm", "reflected_inertia_kgm2",
                    "torque_constant_scale"});
      SimRobotConfig::ActuatorOverride ov;
      ov.joint = a.joint_name;
      if (j.has("coulomb_Nm")) ov.coulomb_Nm = j.number("coulomb_Nm", 0.0, 1e3);
      if (j.has("viscous_Nms_per_rad")) ov.viscous_Nms_per_rad = j.number("viscous_Nms_per_rad", 0.0, 1e3);
      if (j.has("static_Nm")) ov.static_Nm = j.number("static_Nm", 0.0, 1e3);
      if (j.has("reflected_inertia_kgm2")) ov.reflected_inertia_kgm2 = j.number("reflected_inertia_kgm2", 0.0, 100.0);
      if (j.has("torque_constant_scale")) ov.torque_constant_scale = j.number("torque_constant_scale", 0.1, 10.0);
      c.actuator_overrides.push_back(ov);
    }
    // Any key that is not a joint of actuators.yaml is an error.
    for (const std::string& key : o.keys()) {
      if (c.actuators.index_of(key) < 0) throw o.error(key, "unknown joint (not in " + c.actuators_path + ")");
    }
  }
  c.friction_scale = p.number_or("friction_scale", 1.0, 0.0, 10.0);
  if (p.has("friction")) {
    const YamlReader f = p.at("friction");
    f.allow_keys({"breakaway_velocity_rad_s"});
    c.friction.breakaway_velocity_rad_s = f.number_or("breakaway_velocity_rad_s", 1e-3, 1e-6, 1.0);
  }

  if (p.has("noise")) {
    const YamlReader z = p.at("noise");
    z.allow_keys({"torque_sensor_std_Nm", "torque_sensor_offset_Nm", "velocity_std_rad_s", "current_std_A",
                  "encoder_counts_per_rev"});
    c.noise.torque_sensor_std_Nm = z.number_or("torque_sensor_std_Nm", c.noise.torque_sensor_std_Nm, 0.0, 10.0);
    if (z.has("torque_sensor_offset_Nm")) c.noise.torque_sensor_offset_Nm = per_joint(z, "torque_sensor_offset_Nm", n, -10.0, 10.0);
    c.noise.velocity_std_rad_s = z.number_or("velocity_std_rad_s", c.noise.velocity_std_rad_s, 0.0, 1.0);
    c.noise.current_std_A = z.number_or("current_std_A", c.noise.current_std_A, 0.0, 10.0);
    c.noise.encoder_counts_per_rev = z.number_or("encoder_counts_per_rev", c.noise.encoder_counts_per_rev, 0.0, 1e12);
  }

  if (p.has("ft_sensor")) {
    const YamlReader f = p.at("ft_sensor");
    f.allow_keys({"flange_site", "sensor_offset_m", "flange_side_mass_kg", "flange_side_com_m",
                  "flange_side_inertia_kgm2", "rate_Hz", "force_std_N", "torque_std_Nm", "force_bias_N",
                  "torque_bias_Nm"});
    auto& s = c.ft_sensor;
    s.flange_site = f.text_or("flange_site", s.flange_site);
    s.sensor_offset_m = f.number_or("sensor_offset_m", s.sensor_offset_m, 0.0, 1.0);
    s.flange_side_mass_kg = f.number_or("flange_side_mass_kg", s.flange_side_mass_kg, 1e-4, 100.0);
    s.flange_side_com_m = vector3_or(f, "flange_side_com_m", s.flange_side_com_m, -1.0, 1.0);
    s.flange_side_inertia_kgm2 = vector3_or(f, "flange_side_inertia_kgm2", s.flange_side_inertia_kgm2, 1e-9, 10.0);
    s.rate_Hz = f.number_or("rate_Hz", s.rate_Hz, 1.0, 100000.0);
    s.force_std_N = f.number_or("force_std_N", s.force_std_N, 0.0, 100.0);
    s.torque_std_Nm = f.number_or("torque_std_Nm", s.torque_std_Nm, 0.0, 10.0);
    s.force_bias_N = vector3_or(f, "force_bias_N", s.force_bias_N, -1000.0, 1000.0);
    s.torque_bias_Nm = vector3_or(f, "torque_bias_Nm", s.torque_bias_Nm, -100.0, 100.0);
  }

  if (p.has("tool")) {
    const YamlReader t = p.at("tool");
    t.allow_keys({"mass_kg", "com_m", "inertia_kgm2"});
    c.tool.mass_kg = t.number_or("mass_kg", c.tool.mass_kg, 1e-4, 100.0);
    c.tool.com_m = vector3_or(t, "com_m", c.tool.com_m, -1.0, 1.0);
    c.tool.inertia_kgm2 = vector3_or(t, "inertia_kgm2", c.tool.inertia_kgm2, 1e-9, 10.0);
  }

  if (p.has("mismatch")) {
    const YamlReader m = p.at("mismatch");
    m.allow_keys({"enabled", "seed", "mass_fraction", "com_fraction", "inertia_fraction", "torque_constant_fraction"});
    c.mismatch.enabled = m.boolean_or("enabled", false);
    c.mismatch.seed = static_cast<std::uint64_t>(m.integer_or("seed", 7, 0, (1LL << 62)));
    c.mismatch.mass_fraction = m.number_or("mass_fraction", c.mismatch.mass_fraction, 0.0, 0.5);
    c.mismatch.com_fraction = m.number_or("com_fraction", c.mismatch.com_fraction, 0.0, 0.5);
    c.mismatch.inertia_fraction = m.number_or("inertia_fraction", c.mismatch.inertia_fraction, 0.0, 0.5);
    c.mismatch.torque_constant_fraction =
        m.number_or("torque_constant_fraction", c.mismatch.torque_constant_fraction, 0.0, 0.5);
  }

  if (p.has("vendor")) {
    const YamlReader v = p.at("vendor");
    v.allow_keys({"position", "torque", "torque_high_velocity"});
    if (v.has("position")) {
      const YamlReader pos = v.at("position");
      pos.allow_keys({"kp_Nm_per_rad", "kd_Nms_per_rad", "ki_Nm_per_rad_s", "integral_limit_Nm"});
      if (pos.has("kp_Nm_per_rad")) c.vendor.position_kp_Nm_per_rad = per_joint(pos, "kp_Nm_per_rad", n, 0.0, 1e6);
      if (pos.has("kd_Nms_per_rad")) c.vendor.position_kd_Nms_per_rad = per_joint(pos, "kd_Nms_per_rad", n, 0.0, 1e4);
      if (pos.has("ki_Nm_per_rad_s")) c.vendor.position_ki_Nm_per_rad_s = per_joint(pos, "ki_Nm_per_rad_s", n, 0.0, 1e7);
      if (pos.has("integral_limit_Nm")) c.vendor.position_integral_limit_Nm = per_joint(pos, "integral_limit_Nm", n, 0.0, 1e4);
    }
    if (v.has("torque")) {
      const YamlReader t = v.at("torque");
      t.allow_keys({"feedback_gain", "velocity_damping_Nms_per_rad"});
      if (t.has("feedback_gain")) c.vendor.torque_feedback_gain = per_joint(t, "feedback_gain", n, 0.0, 0.95);
      if (t.has("velocity_damping_Nms_per_rad")) {
        c.vendor.torque_velocity_damping_Nms_per_rad = per_joint(t, "velocity_damping_Nms_per_rad", n, 0.0, 1e3);
      }
    }
    if (v.has("torque_high_velocity")) {
      const YamlReader h = v.at("torque_high_velocity");
      h.allow_keys({"numerator", "denominator", "rate_Hz"});
      if (h.has("numerator")) c.vendor.high_velocity_numerator = h.numbers("numerator", -1, -1e6, 1e6);
      if (h.has("denominator")) c.vendor.high_velocity_denominator = h.numbers("denominator", -1, -1e6, 1e6);
      c.vendor.high_velocity_rate_Hz = h.number_or("rate_Hz", c.vendor.high_velocity_rate_Hz, 1.0, 100000.0);
    }
  }

  if (p.has("drop_test")) {
    const YamlReader d = p.at("drop_test");
    d.allow_keys({"enabled", "mass_kg", "radius_m", "cable_length_m", "cable_stiffness_N_per_m",
                  "cable_damping_Ns_per_m", "anchor_m", "release_time_s", "latch_stiffness_N_per_m"});
    auto& s = c.drop_test;
    s.enabled = d.boolean_or("enabled", false);
    s.mass_kg = d.number_or("mass_kg", s.mass_kg, 1e-3, 100.0);
    s.radius_m = d.number_or("radius_m", s.radius_m, 1e-3, 0.5);
    s.cable_length_m = d.number_or("cable_length_m", s.cable_length_m, 0.0, 10.0);
    s.cable_stiffness_N_per_m = d.number_or("cable_stiffness_N_per_m", s.cable_stiffness_N_per_m, 1.0, 1e7);
    s.cable_damping_Ns_per_m = d.number_or("cable_damping_Ns_per_m", s.cable_damping_Ns_per_m, 0.0, 1e5);
    s.anchor_m = vector3_or(d, "anchor_m", s.anchor_m, -1.0, 1.0);
    s.release_time_s = d.number_or("release_time_s", s.release_time_s, 0.0, kHuge);
    s.latch_stiffness_N_per_m = d.number_or("latch_stiffness_N_per_m", s.latch_stiffness_N_per_m, 1.0, 1e7);
  }

  if (p.has("floor")) {
    const YamlReader f = p.at("floor");
    f.allow_keys({"enabled", "height_m"});
    c.floor.enabled = f.boolean_or("enabled", false);
    c.floor.height_m = f.number_or("height_m", 0.0, -10.0, 10.0);
  }

  if (p.has("disturbances")) {
    const YamlReader list = p.at("disturbances");
    list.expect_sequence();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YamlReader e = list.at(i);
      e.allow_keys({"body", "point_m", "frame", "force_N", "torque_Nm", "profile", "start_s", "duration_s", "rise_s"});
      ExternalForce f;
      f.body = e.text("body");
      f.point_m = vector3_or(e, "point_m", Eigen::Vector3d::Zero(), -10.0, 10.0);
      f.frame = e.choice_or("frame", "world", {"world", "local"}) == "world" ? ExternalForce::Frame::kWorld
                                                                            : ExternalForce::Frame::kLocal;
      f.force_N = vector3_or(e, "force_N", Eigen::Vector3d::Zero(), -1e4, 1e4);
      f.torque_Nm = vector3_or(e, "torque_Nm", Eigen::Vector3d::Zero(), -1e3, 1e3);
      f.profile = parse_profile(e.choice("profile", {"step", "ramp", "half_sine"}));
      f.start_s = e.number("start_s", 0.0, kHuge);
      f.duration_s = e.number("duration_s", 1e-6, kHuge);
      f.rise_s = e.number_or("rise_s", f.duration_s, 0.0, kHuge);
      if (f.profile == ExternalForce::Profile::kRamp && f.rise_s > f.duration_s) {
        throw e.error("rise_s", "must not exceed duration_s");
      }
      c.disturbances.push_back(f);
    }
  }

  if (p.has("random_pushes")) {
    const YamlReader r = p.at("random_pushes");
    r.allow_keys({"enabled", "links", "start_s", "min_interval_s", "max_interval_s", "min_force_N", "max_force_N",
                  "min_duration_s", "max_duration_s", "profile"});
    auto& s = c.random_pushes;
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

// Defaults of the vendor loops by actuator size; see KinovaDriveEmulator and
// robots/kinova_gen3/README.md ("Simulated plant") for why these values.
void SimRobotConfig::fill_defaults() {
  auto& v = vendor;
  const int n = actuators.size();
  auto fill = [&](std::vector<double>& out, double large, double small) {
    if (!out.empty()) return;
    for (int i = 0; i < n; ++i) out.push_back(actuators[i].size == ActuatorSize::kLarge ? large : small);
  };
  fill(v.position_kp_Nm_per_rad, 12000.0, 3000.0);
  fill(v.position_kd_Nms_per_rad, 150.0, 15.0);
  fill(v.position_ki_Nm_per_rad_s, 60000.0, 15000.0);
  fill(v.position_integral_limit_Nm, 60.0, 30.0);
  fill(v.torque_feedback_gain, 0.5, 0.5);
  fill(v.torque_velocity_damping_Nms_per_rad, 15.0, 5.0);
  if (noise.torque_sensor_offset_Nm.empty()) noise.torque_sensor_offset_Nm.assign(static_cast<std::size_t>(n), 0.0);
}

int SimRobotConfig::substeps_per_cycle() const {
  return static_cast<int>(std::lround(control_period_s * physics_rate_Hz));
}

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
  check_size(*this, initial_q_rad, "plant.initial.q_rad");
  check_size(*this, noise.torque_sensor_offset_Nm, "plant.noise.torque_sensor_offset_Nm");
  check_size(*this, vendor.position_kp_Nm_per_rad, "plant.vendor.position.kp_Nm_per_rad");
  check_size(*this, vendor.position_kd_Nms_per_rad, "plant.vendor.position.kd_Nms_per_rad");
  check_size(*this, vendor.position_ki_Nm_per_rad_s, "plant.vendor.position.ki_Nm_per_rad_s");
  check_size(*this, vendor.position_integral_limit_Nm, "plant.vendor.position.integral_limit_Nm");
  check_size(*this, vendor.torque_feedback_gain, "plant.vendor.torque.feedback_gain");
  check_size(*this, vendor.torque_velocity_damping_Nms_per_rad, "plant.vendor.torque.velocity_damping_Nms_per_rad");
  for (double g : vendor.torque_feedback_gain) {
    // The torque loop closes through the (almost algebraic) transmission: it needs gain < 1 to be
    // stable with a one-sample measurement delay (see KinovaDriveEmulator).
    if (!(g >= 0.0 && g < 0.95)) throw ConfigError(f, "plant.vendor.torque.feedback_gain", "must be in [0, 0.95)");
  }
  const auto& num = vendor.high_velocity_numerator;
  const auto& den = vendor.high_velocity_denominator;
  if (num.empty() || den.empty() || num.size() > 6 || den.size() > 6 || den[0] == 0.0) {
    throw ConfigError(f, "plant.vendor.torque_high_velocity", "needs 1..6 numerator and denominator coefficients, a0 != 0");
  }
  for (const auto& o : actuator_overrides) {
    if (actuators.index_of(o.joint) < 0) throw ConfigError(f, "plant.actuator_overrides." + o.joint, "unknown joint");
  }
  const ActuatorTable plant = plant_actuators();
  for (int i = 0; i < plant.size(); ++i) {
    if (plant[i].reflected_inertia_kgm2 < 1e-3) {
      // The stick-slip friction's presliding stiffness is scaled on it (see StickSlipFriction).
      throw ConfigError(f, "plant.actuator_overrides." + plant[i].joint_name + ".reflected_inertia_kgm2",
                        "plant reflected rotor inertia must be >= 1e-3 kg.m^2");
    }
    if (plant[i].friction.static_Nm < plant[i].friction.coulomb_Nm) {
      throw ConfigError(f, "plant.actuator_overrides." + plant[i].joint_name + ".static_Nm",
                        "plant static friction must be >= its Coulomb friction");
    }
  }
  if (drop_test.enabled && !(drop_test.cable_length_m > 0.0)) {
    throw ConfigError(f, "plant.drop_test.cable_length_m", "must be positive");
  }
  const auto& r = random_pushes;
  if (r.enabled) {
    if (r.max_force_N < r.min_force_N || r.max_interval_s < r.min_interval_s || r.max_duration_s < r.min_duration_s) {
      throw ConfigError(f, "plant.random_pushes", "every max_* must be >= its min_*");
    }
    if (!(r.min_duration_s > 0.0)) throw ConfigError(f, "plant.random_pushes.min_duration_s", "must be positive");
  }
  for (std::size_t i = 0; i < disturbances.size(); ++i) {
    const auto& d = disturbances[i];
    const std::string key = "plant.disturbances[" + std::to_string(i) + "]";
    if (d.body.empty()) throw ConfigError(f, key + ".body", "empty body name");
    if (!(d.duration_s > 0.0)) throw ConfigError(f, key + ".duration_s", "must be positive");
    if (!d.force_N.allFinite() || !d.torque_Nm.allFinite() || !d.point_m.allFinite()) {
      throw ConfigError(f, key, "values must be finite");
    }
  }
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
