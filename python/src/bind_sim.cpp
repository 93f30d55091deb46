// phri/sim for Python: the simulated Gen3 (SimRobot, a RobotInterface), its configuration
// (SimRobotConfig, as configs/plant_gen3.yaml), scripted pushes (ExternalForce), random pushes, the
// drop test, and the plant's noise-free truth (views). Also the actuator table (robot/), which
// the configuration carries.
#include "bindings.hpp"

#include <phri/robot/actuator_table.hpp>
#include <phri/sim/sim_robot.hpp>

namespace phri::python {
namespace {

void bind_actuators(py::module_& m) {
  py::class_<FrictionParameters>(m, "FrictionParameters", "Joint friction model (actuators.yaml `friction:`).")
      .def(py::init<>())
      .def_readwrite("coulomb_Nm", &FrictionParameters::coulomb_Nm)
      .def_readwrite("viscous_Nms_per_rad", &FrictionParameters::viscous_Nms_per_rad)
      .def_readwrite("static_Nm", &FrictionParameters::static_Nm)
      .def_readwrite("velocity_threshold_rad_s", &FrictionParameters::velocity_threshold_rad_s)
      .def_readwrite("acceleration_threshold_rad_s2", &FrictionParameters::acceleration_threshold_rad_s2);
  py::class_<ActuatorParameters>(m, "ActuatorParameters", "One joint drive (actuators.yaml).")
      .def(py::init<>())
      .def_readwrite("joint_name", &ActuatorParameters::joint_name)
      .def_readwrite("gear_ratio", &ActuatorParameters::gear_ratio)
      .def_readwrite("torque_constant_Nm_per_A", &ActuatorParameters::torque_constant_Nm_per_A)
      .def_readwrite("rotor_inertia_kgm2", &ActuatorParameters::rotor_inertia_kgm2)
      .def_readwrite("reflected_inertia_kgm2", &ActuatorParameters::reflected_inertia_kgm2)
      .def_readwrite("current_limit_A", &ActuatorParameters::current_limit_A)
      .def_readwrite("torque_limit_Nm", &ActuatorParameters::torque_limit_Nm)
      .def_readwrite("velocity_limit_rad_s", &ActuatorParameters::velocity_limit_rad_s)
      .def_readwrite("friction", &ActuatorParameters::friction)
      .def("torque_per_amp", &ActuatorParameters::torque_per_amp, "K_T G_r [N m/A].");
  py::class_<ActuatorTable>(m, "ActuatorTable", "The drives of every joint, in order (actuators.yaml).")
      .def_static("from_yaml_file", [](const std::filesystem::path& path) { return ActuatorTable::from_yaml_file(path.string()); },
                  py::arg("path"))
      .def_property_readonly("joints", &ActuatorTable::joints, "The drives (copies).")
      .def("index_of", &ActuatorTable::index_of, py::arg("joint_name"), "-1 when absent.")
      .def("__len__", &ActuatorTable::size);
}

void bind_external_force(py::module_& m) {
  py::class_<ExternalForce> c(m, "ExternalForce",
                              "A scripted push: force (and moment) at a point of a body, with a time profile.");
  py::enum_<ExternalForce::Profile>(c, "Profile", "Time profile over [start_s, start_s + duration_s).")
      .value("step", ExternalForce::Profile::kStep)
      .value("ramp", ExternalForce::Profile::kRamp)
      .value("half_sine", ExternalForce::Profile::kHalfSine);
  py::enum_<ExternalForce::Frame>(c, "Frame", "Axes of force_N and torque_Nm.")
      .value("world", ExternalForce::Frame::kWorld)
      .value("local", ExternalForce::Frame::kLocal);
  c.def(py::init<>())
      .def(py::init([](std::string body, const Eigen::Vector3d& force, double start, double duration,
                       ExternalForce::Profile profile) {
             ExternalForce f;
             f.body = std::move(body);
             f.force_N = force;
             f.start_s = start;
             f.duration_s = duration;
             f.profile = profile;
             return f;
           }),
           py::arg("body"), py::arg("force_N"), py::arg("start_s"), py::arg("duration_s"),
           py::arg("profile") = ExternalForce::Profile::kHalfSine, "A push on `body` in world axes at its origin.")
      .def_readwrite("body", &ExternalForce::body, "MJCF body name (arm link, 'tool', 'drop_mass').")
      .def_readwrite("point_m", &ExternalForce::point_m, "Application point in the body frame [m].")
      .def_readwrite("frame", &ExternalForce::frame)
      .def_readwrite("force_N", &ExternalForce::force_N)
      .def_readwrite("torque_Nm", &ExternalForce::torque_Nm)
      .def_readwrite("profile", &ExternalForce::profile)
      .def_readwrite("start_s", &ExternalForce::start_s)
      .def_readwrite("duration_s", &ExternalForce::duration_s)
      .def_readwrite("rise_s", &ExternalForce::rise_s, "Ramp only.")
      .def("scale_at", &ExternalForce::scale_at, py::arg("t"), "Profile value in [0, 1] at time t.");
  py::class_<RandomPushSettings>(m, "RandomPushSettings", "Seeded random pushes on the arm's links.")
      .def(py::init<>())
      .def_readwrite("enabled", &RandomPushSettings::enabled)
      .def_readwrite("links", &RandomPushSettings::links)
      .def_readwrite("start_s", &RandomPushSettings::start_s)
      .def_readwrite("min_interval_s", &RandomPushSettings::min_interval_s)
      .def_readwrite("max_interval_s", &RandomPushSettings::max_interval_s)
      .def_readwrite("min_force_N", &RandomPushSettings::min_force_N)
      .def_readwrite("max_force_N", &RandomPushSettings::max_force_N)
      .def_readwrite("min_duration_s", &RandomPushSettings::min_duration_s)
      .def_readwrite("max_duration_s", &RandomPushSettings::max_duration_s)
      .def_readwrite("profile", &RandomPushSettings::profile);
}

void bind_config_parts(py::class_<SimRobotConfig>& c) {
  using C = SimRobotConfig;
  py::class_<C::Noise>(c, "Noise", "Joint sensor noise.")
      .def_readwrite("torque_sensor_std_Nm", &C::Noise::torque_sensor_std_Nm)
      .def_readwrite("torque_sensor_offset_Nm", &C::Noise::torque_sensor_offset_Nm)
      .def_readwrite("velocity_std_rad_s", &C::Noise::velocity_std_rad_s)
      .def_readwrite("current_std_A", &C::Noise::current_std_A)
      .def_readwrite("encoder_counts_per_rev", &C::Noise::encoder_counts_per_rev);
  py::class_<C::Tool>(c, "Tool", "The tool below the F/T sensor.")
      .def_readwrite("mass_kg", &C::Tool::mass_kg)
      .def_readwrite("com_m", &C::Tool::com_m)
      .def_readwrite("inertia_kgm2", &C::Tool::inertia_kgm2);
  py::class_<C::Mismatch>(c, "Mismatch", "Plant link inertials and drive gains off the controller's model.")
      .def_readwrite("enabled", &C::Mismatch::enabled)
      .def_readwrite("seed", &C::Mismatch::seed)
      .def_readwrite("mass_fraction", &C::Mismatch::mass_fraction)
      .def_readwrite("com_fraction", &C::Mismatch::com_fraction)
      .def_readwrite("inertia_fraction", &C::Mismatch::inertia_fraction)
      .def_readwrite("torque_constant_fraction", &C::Mismatch::torque_constant_fraction);
  py::class_<C::DropTest>(c, "DropTest", "The paper's drop test: a mass on a slack cable under the tool, released.")
      .def_readwrite("enabled", &C::DropTest::enabled)
      .def_readwrite("mass_kg", &C::DropTest::mass_kg)
      .def_readwrite("radius_m", &C::DropTest::radius_m)
      .def_readwrite("cable_length_m", &C::DropTest::cable_length_m)
      .def_readwrite("cable_stiffness_N_per_m", &C::DropTest::cable_stiffness_N_per_m)
      .def_readwrite("cable_damping_Ns_per_m", &C::DropTest::cable_damping_Ns_per_m)
      .def_readwrite("anchor_m", &C::DropTest::anchor_m, "Cable anchor in the sensor frame [m].")
      .def_readwrite("release_time_s", &C::DropTest::release_time_s)
      .def_readwrite("latch_stiffness_N_per_m", &C::DropTest::latch_stiffness_N_per_m)
      .def_readwrite("release_vertical_spread_m", &C::DropTest::release_vertical_spread_m, "Hand's release: fall height +- [m].")
      .def_readwrite("release_horizontal_spread_m", &C::DropTest::release_horizontal_spread_m, "Hand's release: sideways +- [m].")
      .def_readwrite("held_by_hand", &C::DropTest::held_by_hand, "True: a hand, not the tool, holds the mass until release.");
  py::enum_<C::Elasticity::Encoder>(c, "Encoder", "The encoder the vendor position servo closes on.")
      .value("motor", C::Elasticity::Encoder::kMotor)
      .value("motor_compensated", C::Elasticity::Encoder::kMotorCompensated)
      .value("link", C::Elasticity::Encoder::kLink);
  py::class_<C::Elasticity>(c, "Elasticity", "Joint elasticity: rotor -- torsional spring -- link.")
      .def_readwrite("enabled", &C::Elasticity::enabled)
      .def_readwrite("stiffness_Nm_per_rad", &C::Elasticity::stiffness_Nm_per_rad, "Per joint; a copy: assign a whole list.")
      .def_readwrite("damping_ratio", &C::Elasticity::damping_ratio)
      .def_readwrite("position_loop_encoder", &C::Elasticity::position_loop_encoder);
  py::class_<C::FtSensor>(c, "FtSensor", "The F/T sensor between flange and tool.")
      .def_readwrite("rate_Hz", &C::FtSensor::rate_Hz)
      .def_readwrite("force_std_N", &C::FtSensor::force_std_N)
      .def_readwrite("torque_std_Nm", &C::FtSensor::torque_std_Nm)
      .def_readwrite("force_bias_N", &C::FtSensor::force_bias_N)
      .def_readwrite("torque_bias_Nm", &C::FtSensor::torque_bias_Nm);
  py::class_<C::Floor>(c, "Floor").def_readwrite("enabled", &C::Floor::enabled).def_readwrite("height_m", &C::Floor::height_m);
}

void bind_config(py::module_& m) {
  using C = SimRobotConfig;
  py::class_<C> c(m, "SimRobotConfig",
                  "Everything the simulated arm needs (configs/plant_gen3.yaml). Nested settings are edited in place "
                  "(config.drop_test.enabled = True); list fields are copies: assign a whole new list.");
  bind_config_parts(c);
  c.def(py::init<>())
      .def_static("from_yaml_file", [](const std::filesystem::path& path) { return C::from_yaml_file(path.string()); },
                  py::arg("path"), "Loads and validates; ConfigError with the key path.")
      .def_static("from_yaml_string", &C::from_yaml_string, py::arg("yaml"), py::arg("source_name"), py::arg("base_dir"))
      .def("fill_defaults", &C::fill_defaults, "Per-joint vectors left empty get their defaults (vendor gains, zero offsets).")
      .def("validate", &C::validate, "Cross-field checks; ConfigError with the key path.")
      .def("plant_actuators", &C::plant_actuators, "The plant's drives: actuators with the overrides applied.")
      .def("ft_sensor_present", &C::ft_sensor_present, "The arm carries an F/T sensor (its end of arm has one).")
      .def_property_readonly("dof", &C::dof)
      .def("substeps_per_cycle", &C::substeps_per_cycle, "Physics steps per control period.")
      .def_readwrite("source", &C::source)
      .def_readwrite("mjcf_path", &C::mjcf_path)
      .def_readwrite("urdf_path", &C::urdf_path, "The URDF the arm's MJCF is generated from, when mjcf_path is empty.")
      .def_readwrite("locked_joints", &C::locked_joints, "URDF joints welded at 0 in a generated plant.")
      .def_readwrite("balance_inertia", &C::balance_inertia, "Generated plant: MuJoCo's balanceinertia.")
      .def_readwrite("actuators_path", &C::actuators_path)
      .def_readwrite("actuators", &C::actuators)
      .def_readwrite("physics_rate_Hz", &C::physics_rate_Hz)
      .def_readwrite("control_period_s", &C::control_period_s)
      .def_readwrite("initial_q_rad", &C::initial_q_rad, "One per joint [rad] (a list: assign a new one).")
      .def_readwrite("seed", &C::seed, "Sensor noise and random pushes.")
      .def_readwrite("friction_scale", &C::friction_scale)
      .def_readwrite("noise", &C::noise)
      .def_readwrite("ft_sensor", &C::ft_sensor)
      .def_readwrite("tool", &C::tool)
      .def_readwrite("mismatch", &C::mismatch)
      .def_readwrite("drop_test", &C::drop_test)
      .def_readwrite("elasticity", &C::elasticity)
      .def_readwrite("floor", &C::floor)
      .def_readwrite("disturbances", &C::disturbances, "Scripted pushes (a list: assign a new one).")
      .def_readwrite("random_pushes", &C::random_pushes);
}

// Truth's vectors as read-only views (owner: the robot, which keeps the truth up to date).
void bind_truth(py::class_<SimRobot, RobotInterface>& robot) {
  using T = SimRobot::Truth;
  py::class_<T> t(robot, "Truth", "Noise-free plant quantities no sensor gives (views, updated by every read()).");
  auto vector = [&t](const char* name, Eigen::VectorXd T::*member, const char* doc) {
    t.def_property_readonly(name, [member](py::object self) { return vector_view(self.cast<const T&>().*member, self); }, doc);
  };
  auto vector3 = [&t](const char* name, Eigen::Vector3d T::*member, const char* doc) {
    t.def_property_readonly(name, [member](py::object self) { return vector_view((self.cast<const T&>().*member).data(), 3, self); }, doc);
  };
  t.def_readonly("time_s", &T::time_s);
  vector("q_rad", &T::q_rad, "Joint positions [rad].");
  vector("qd_rad_s", &T::qd_rad_s, "Joint velocities [rad/s].");
  vector("qdd_rad_s2", &T::qdd_rad_s2, "Joint accelerations of the last physics step [rad/s^2].");
  vector("current_A", &T::current_A, "Applied (saturated) motor current [A].");
  vector("tau_motor_Nm", &T::tau_motor_Nm, "K_T G_r i [N m].");
  vector("tau_friction_Nm", &T::tau_friction_Nm, "Friction on the joint (viscous + dry) [N m].");
  vector("tau_transmitted_Nm", &T::tau_transmitted_Nm, "What the torque sensor measures, without noise [N m].");
  t.def_property_readonly("wrench_sensor", [](py::object self) { return vector_view(self.cast<const T&>().wrench_sensor.data(), 6, self); },
                          "F/T at its last sample, without noise or bias.");
  vector3("sensor_position_m", &T::sensor_position_m, "F/T frame origin in the world [m].");
  t.def_readonly("sensor_rotation", &T::sensor_rotation, "F/T frame axes in the world (a copy).");
  t.def_readonly("drop_released", &T::drop_released);
  vector3("drop_mass_position_m", &T::drop_mass_position_m, "Drop mass centre in the world [m].");
  vector3("drop_mass_velocity_m_s", &T::drop_mass_velocity_m_s, "[m/s].");
  t.def_readonly("cable_length_m", &T::cable_length_m, "Anchor to mass centre [m].");
  t.def_readonly("cable_force_N", &T::cable_force_N, "Cable tension (0 while slack) [N].");
}

void bind_sim_robot(py::module_& m) {
  py::class_<SimRobot, RobotInterface> c(m, "SimRobot",
                                         "The simulated Gen3: MuJoCo physics at 4 kHz, drives, friction, vendor loops, "
                                         "sensors, pushes, drop test. read() advances one control period.");
  bind_truth(c);
  c.def(py::init<const SimRobotConfig&>(), py::arg("config"), "Builds the plant; ConfigError on a bad configuration.")
      .def("state", &SimRobot::state, py::return_value_policy::reference_internal, "The latest state, without advancing.")
      .def("truth", &SimRobot::truth, py::return_value_policy::reference_internal, "The plant's noise-free truth.")
      .def_property_readonly("config", [](const SimRobot& r) { return SimRobotConfig(r.config()); }, "The configuration (a copy).")
      .def("reset", &SimRobot::reset, "Back to the initial state: same configuration and seeds, so the same run again.")
      .def("body_id", &SimRobot::body_id, py::arg("name"), "The scene body named `name`; -1 when there is none.")
      .def("set_live_disturbance", &SimRobot::set_live_disturbance, py::arg("body"), py::arg("force"),
           "One push chosen while running, on body `body` (body_id) from the next read(); body -1 clears it.")
      .def_property_readonly("scene_mjcf", &SimRobot::scene_mjcf, "MJCF text of the scene that was loaded.");
}

}  // namespace

void bind_sim(py::module_& m) {
  bind_actuators(m);
  bind_external_force(m);
  bind_config(m);
  bind_sim_robot(m);
}

}  // namespace phri::python
