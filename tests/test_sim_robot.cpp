// ctest-labels: physics
// The simulated Kinova Gen3 (phri::SimRobot) against independent references: gravity torques of
// phri's own URDF model plus the configured payload, closed-form friction and vendor-loop
// behaviour, the tool's weight in the F/T sensor frame, MuJoCo's own quantities. Short simulated
// horizons (a few seconds at most); nothing here measures time.
#include <phri/app/loop_clock.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>
#include <phri/sim/site_wrench_sensor.hpp>
#include <phri/core/random_generator.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace {

using phri::LowLevelMode;
using phri::RobotCommand;
using phri::SimRobot;
using phri::SimRobotConfig;
using phri::WriteStatus;

const std::string kRoot = PHRI_SOURCE_DIR;
// The paper's postureTarget, a partly extended pose with gravity on joints 2, 4, 6.
const std::vector<double> kTarget = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

SimRobotConfig load(bool noise = true) {
  SimRobotConfig c = SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kTarget;
  if (!noise) {
    c.noise.torque_sensor_std_Nm = 0.0;
    c.noise.velocity_std_rad_s = 0.0;
    c.noise.current_std_A = 0.0;
    c.noise.torque_sensor_offset_Nm.assign(7, 0.0);
    c.ft_sensor.force_std_N = 0.0;
    c.ft_sensor.torque_std_Nm = 0.0;
    c.ft_sensor.force_bias_N.setZero();
    c.ft_sensor.torque_bias_Nm.setZero();
  }
  return c;
}

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// The controller's view of the arm: gen3.urdf (phri::Model), plus point masses for the scene's
// payload: adapter + sensor body at its COM in the flange frame, the tool at its COM in the sensor
// frame (placed by the sensor's mount on the flange). end_effector_link is the flange (= MJCF site).
struct Reference {
  phri::Model model;
  phri::Data data;
  int flange_com, tool_com, flange;
  double flange_mass, tool_mass;

  static phri::Model make(const SimRobotConfig& c) {
    phri::ModelOptions o;
    Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
    a.translation() = c.ft_sensor.flange_side_com_m;
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() = c.ft_sensor.sensor_mount * c.tool.com_m;
    o.extra_frames.push_back({"flange_com", "end_effector_link", a});
    o.extra_frames.push_back({"tool_com", "end_effector_link", t});
    return phri::Model::from_urdf_file(kRoot + "/robots/kinova_gen3/gen3.urdf", o);
  }
  explicit Reference(const SimRobotConfig& c)
      : model(make(c)),
        data(model),
        flange_com(model.frame_id("flange_com")),
        tool_com(model.frame_id("tool_com")),
        flange(model.frame_id("end_effector_link")),
        flange_mass(c.ft_sensor.flange_side_mass_kg),
        tool_mass(c.tool.mass_kg) {}

  /// Holding torque g(q) of arm + payload.
  Eigen::VectorXd gravity(const Eigen::VectorXd& q) {
    Eigen::VectorXd g = phri::compute_gravity(model, data, q);
    phri::forward_kinematics(model, data, q);
    phri::update_frame_placements(model, data);
    Eigen::MatrixXd J(6, model.nv());
    const Eigen::Vector3d gravity_vector = model.gravity();
    for (auto [frame, mass] : {std::pair{flange_com, flange_mass}, std::pair{tool_com, tool_mass}}) {
      phri::frame_jacobian(model, data, frame, phri::ReferenceFrame::kLocalWorldAligned, J);
      g -= J.topRows<3>().transpose() * (mass * gravity_vector);
    }
    return g;
  }
  /// Orientation of the flange (= the F/T sensor axes) in the world.
  Eigen::Matrix3d flange_rotation(const Eigen::VectorXd& q) {
    phri::forward_kinematics(model, data, q);
    phri::update_frame_placements(model, data);
    return data.frame_placements[static_cast<std::size_t>(flange)].linear();
  }
};

Eigen::VectorXd currents_for(const SimRobot& robot, const Eigen::VectorXd& tau) {
  Eigen::VectorXd i(tau.size());
  for (int k = 0; k < tau.size(); ++k) i[k] = tau[k] / robot.plant_actuators()[k].torque_per_amp();
  return i;
}

// -------------------------------------------------------------------------- scene and gravity
TEST(SimRobotScene, MujocoGravityEqualsUrdfPlusPayload) {
  const SimRobotConfig c = load(false);
  SimRobot robot(c);
  Reference ref(c);
  const Eigen::VectorXd g = ref.gravity(to_vector(kTarget));
  const mjData* d = robot.mujoco_data();
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(d->qfrc_bias[i], g[i], 1e-9) << "joint " << i + 1;
  // The arm file itself is untouched: the scene adds the adapter and tool bodies around it.
  EXPECT_NE(robot.scene_mjcf().find("name=\"tool\""), std::string::npos);
  EXPECT_EQ(robot.scene_mjcf().find("<keyframe"), std::string::npos);
  const mjModel* m = robot.mujoco_model();
  EXPECT_NEAR(m->body_mass[mj_name2id(m, mjOBJ_BODY, phri::SimScene::kToolBody)], 0.3, 1e-12);
  EXPECT_NEAR(m->dof_armature[0], 0.03, 1e-12);
}

// The plant cannot start beyond its MJCF's joint range (joint_2: +-2.24 rad).
TEST(SimRobotScene, InitialPostureBeyondTheJointRangeIsRefused) {
  SimRobotConfig c = load(false);
  c.initial_q_rad[1] = 3.0;
  phri::test::expect_config_error([&] { phri::SimRobot robot(c); },
                                  {.element = "plant.initial.q_rad[1]", .mentions = {"joint_2", "2.24"}});
}

TEST(SimRobotPhysics, GravityHeldInCurrentModeDoesNotDrift) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  Reference ref(c);
  const Eigen::VectorXd q0 = to_vector(kTarget);
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kCurrent;
  cmd.current_A = currents_for(robot, ref.gravity(q0));
  double drift = 0.0;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(robot.write(cmd), WriteStatus::kOk);
    robot.read();
    drift = std::max(drift, (robot.truth().q_rad - q0).cwiseAbs().maxCoeff());
  }
  // Exact gravity, and friction holds whatever model error is left: only presliding (< 1e-4 rad).
  std::printf("gravity hold in Current mode, 2 s: max |q - q0| = %.2e rad\n", drift);
  EXPECT_LT(drift, 1e-4);
  EXPECT_EQ(robot.state().mode, LowLevelMode::kCurrent);
  EXPECT_FALSE(robot.state().fault);

  // Under-compensated by 0.8 x the static level on every joint: still held by stiction.
  SimRobot robot2(c);
  Eigen::VectorXd tau = ref.gravity(q0);
  for (int i = 0; i < 7; ++i) tau[i] -= 0.8 * robot2.plant_actuators()[i].friction.static_Nm;
  cmd.current_A = currents_for(robot2, tau);
  for (int k = 0; k < 1000; ++k) {
    robot2.write(cmd);
    robot2.read();
  }
  EXPECT_LT((robot2.truth().q_rad - q0).cwiseAbs().maxCoeff(), 1e-4);
}

// Joint 1 (vertical axis: no gravity) under gravity compensation plus an extra torque.
struct StictionRun {
  double displacement, velocity;
  bool sliding;
};
StictionRun run_joint1(SimRobotConfig c, double extra, double seconds) {
  SimRobot robot(c);
  Reference ref(c);
  const Eigen::VectorXd q0 = to_vector(kTarget);
  Eigen::VectorXd tau = ref.gravity(q0);
  tau[0] += extra;
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kCurrent;
  cmd.current_A = currents_for(robot, tau);
  for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) {
    robot.write(cmd);
    robot.read();
  }
  return {robot.truth().q_rad[0] - q0[0], robot.truth().qd_rad_s[0], std::abs(robot.truth().qd_rad_s[0]) > 1e-3};
}

TEST(SimRobotPhysics, JointSticksBelowStaticFrictionAndSlidesAbove) {
  SimRobotConfig c = load(false);
  const double fs = c.actuators[0].friction.static_Nm;  // 2.15 N.m (paper), = Coulomb
  const double b = c.actuators[0].friction.viscous_Nms_per_rad;
  const auto below = run_joint1(c, 0.95 * fs, 1.0);
  const auto above = run_joint1(c, 1.05 * fs, 4.0);
  std::printf("stiction joint 1 (static %.2f N.m): 0.95 x -> moved %.2e rad; 1.05 x -> %.3f rad/s "
              "(closed form %.4f)\n", fs, below.displacement, above.velocity, 0.05 * fs / b);
  EXPECT_LT(std::abs(below.displacement), 1e-4);
  EXPECT_FALSE(below.sliding);
  // Sliding: net torque 1.05 fs - coulomb - b qd -> terminal speed 0.05 fs / b (time constant I/b).
  EXPECT_GT(above.displacement, 0.05);
  EXPECT_NEAR(above.velocity, 0.05 * fs / b, 0.03 * 0.05 * fs / b);

  // Static above Coulomb (plant override, the controller's table unchanged): stuck at 1.3 x
  // Coulomb, slides at 1.5 x Coulomb against the Coulomb level only.
  SimRobotConfig::ActuatorOverride o;
  o.joint = "joint_1";
  o.static_Nm = 1.4 * c.actuators[0].friction.coulomb_Nm;
  c.actuator_overrides.push_back(o);
  const double fc = c.actuators[0].friction.coulomb_Nm;
  const auto stuck = run_joint1(c, 1.3 * fc, 1.0);
  const auto slides = run_joint1(c, 1.5 * fc, 4.0);
  EXPECT_LT(std::abs(stuck.displacement), 1e-4);
  EXPECT_NEAR(slides.velocity, 0.5 * fc / b, 0.03 * 0.5 * fc / b);
}

// ------------------------------------------------------------------------------------ sensors
TEST(SimRobotSensors, TorqueSensorAtRestReadsGravity) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  Reference ref(c);
  const Eigen::VectorXd g = ref.gravity(to_vector(kTarget));
  for (int k = 0; k < 300; ++k) robot.read();  // Position mode hold (the default command)
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(7), sum2 = Eigen::VectorXd::Zero(7);
  const int n = 1000;
  for (int k = 0; k < n; ++k) {
    const auto& s = robot.read();
    sum += s.tau_sensor_Nm;
    sum2 += s.tau_sensor_Nm.cwiseAbs2();
  }
  const Eigen::VectorXd mean = sum / n - to_vector(c.noise.torque_sensor_offset_Nm);
  // The spread is the sensor noise plus the torque ripple of the position servo (it turns the
  // drives' velocity noise into real torque, which the sensor sees): use the measured spread.
  const Eigen::VectorXd spread = (sum2 / n - (sum / n).cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
  std::printf("torque sensor at rest - gravity (N.m):");
  for (int i = 0; i < 7; ++i) std::printf(" %+.4f", mean[i] - g[i]);
  std::printf("\n  per-sample spread (N.m):");
  for (int i = 0; i < 7; ++i) std::printf(" %.4f", spread[i]);
  std::printf("\n");
  for (int i = 0; i < 7; ++i) {
    EXPECT_GE(spread[i], 0.9 * c.noise.torque_sensor_std_Nm) << "joint " << i + 1;
    EXPECT_NEAR(mean[i], g[i], 5.0 * spread[i] / std::sqrt(n) + 1e-3) << "joint " << i + 1;
  }
  const auto& s = robot.read();
  EXPECT_TRUE(s.torque.valid);
  EXPECT_EQ(s.torque.sequence, 1302u);  // the initial sample, then one per cycle

  // Current mode with the exact gravity torques: no servo ripple, only the sensor noise.
  SimRobot quiet(c);
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kCurrent;
  cmd.current_A = currents_for(quiet, g);
  sum.setZero();
  for (int k = 0; k < n; ++k) {
    quiet.write(cmd);
    sum += quiet.read().tau_sensor_Nm;
  }
  const Eigen::VectorXd quiet_mean = sum / n - to_vector(c.noise.torque_sensor_offset_Nm);
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(quiet_mean[i], g[i], 5.0 * c.noise.torque_sensor_std_Nm / std::sqrt(n) + 1e-4) << "joint " << i + 1;
  }
}

// The torque sensor measures what the drive transmits to the link: with no external force,
// tau_s = M_link(q) qdd + h(q, qd) exactly (MuJoCo's mass matrix without the rotor armature and its
// bias forces, at the state the step started from), during a violent motion with sliding friction.
TEST(SimRobotSensors, TorqueSensorIsTheTransmittedTorque) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  const mjModel* m = robot.mujoco_model();
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kPosition;
  cmd.q_rad = to_vector(kTarget);
  cmd.q_rad[0] += 0.08;  // steps within the 5 degree following-error bound the robot accepts
  cmd.q_rad[3] -= 0.08;
  cmd.q_rad[6] += 0.08;
  ASSERT_EQ(robot.write(cmd), WriteStatus::kOk);
  std::vector<double> M(static_cast<std::size_t>(m->nv * m->nv));
  double worst = 0.0, largest = 0.0;
  for (int k = 0; k < 600; ++k) {
    if (k == 300) {
      cmd.mode = LowLevelMode::kKinovaTorqueHighVelocity;
      cmd.tau_Nm.setZero();  // let it fall: everything slides
      robot.write(cmd);
    }
    robot.read();
    const mjData* d = robot.mujoco_data();
    mj_fullM(m, M.data(), d->qM);
    const auto& t = robot.truth();
    for (int i = 0; i < 7; ++i) {
      double expected = d->qfrc_bias[i];
      for (int j = 0; j < 7; ++j) {
        const double mij = M[static_cast<std::size_t>(i * m->nv + j)] - (i == j ? m->dof_armature[i] : 0.0);
        expected += mij * t.qdd_rad_s2[j];
      }
      worst = std::max(worst, std::abs(t.tau_transmitted_Nm[i] - expected));
      largest = std::max(largest, std::abs(t.tau_transmitted_Nm[i]));
    }
  }
  std::printf("tau_s vs M_link qdd + h over 0.6 s (max |tau_s| %.1f N.m): worst difference %.2e N.m\n", largest, worst);
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(largest, 20.0);
}

TEST(SimRobotSensors, FtSensorReadsToolWeight) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  Reference ref(c);
  for (int k = 0; k < 200; ++k) robot.read();
  Eigen::Matrix<double, 6, 1> sum = Eigen::Matrix<double, 6, 1>::Zero();
  const int n = 500;
  std::uint32_t last = robot.state().wrench.sequence;
  for (int k = 0; k < n; ++k) {
    const auto& s = robot.read();
    EXPECT_EQ(s.wrench.sequence, last + 1);  // 1 kHz sensor, 1 kHz cycle: a new sample each cycle
    last = s.wrench.sequence;
    sum += s.wrench_sensor;
  }
  Eigen::Matrix<double, 6, 1> mean = sum / n;
  mean.head<3>() -= c.ft_sensor.force_bias_N;
  mean.tail<3>() -= c.ft_sensor.torque_bias_Nm;
  // The tool's weight in the sensor axes (= flange axes from the URDF), and its moment about the
  // sensor origin, com x weight.
  const Eigen::Matrix3d R = ref.flange_rotation(to_vector(kTarget));
  const Eigen::Vector3d weight = R.transpose() * (c.tool.mass_kg * Eigen::Vector3d(0, 0, -9.81));
  const Eigen::Vector3d moment = c.tool.com_m.cross(weight);
  const double tf = 5.0 * c.ft_sensor.force_std_N / std::sqrt(n) + 1e-3;
  const double tm = 5.0 * c.ft_sensor.torque_std_Nm / std::sqrt(n) + 1e-4;
  std::printf("F/T at rest, bias removed: f = (%.4f, %.4f, %.4f) N, |f| = %.4f N (tool weight %.4f N)\n", mean[0],
              mean[1], mean[2], mean.head<3>().norm(), c.tool.mass_kg * 9.81);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(mean[k], weight[k], tf);
    EXPECT_NEAR(mean[3 + k], moment[k], tm);
  }
}

// SiteWrenchSensor, SimRobot's F/T readings, against MuJoCo's own sensor stage, bit for bit: on the
// scene SimRobot builds (drop mass, floor), with forces applied on every body (the tool and its
// parents among them) and the tool pressed into the floor (contacts on the sensor's body and on
// others), after mj_forward and across mj_step (given the velocities from before the step).
TEST(SimRobotSensors, FtReadingsAreMujocosSensorStageBitForBit) {
  SimRobotConfig c = load();
  c.drop_test.enabled = true;
  c.floor.enabled = true;
  SimRobot robot(c);
  mjModel* m = mj_copyModel(nullptr, robot.mujoco_model());
  m->opt.disableflags &= ~(mjDSBL_SENSOR | mjDSBL_CONTACT);
  const int force = mj_name2id(m, mjOBJ_SENSOR, phri::SimScene::kForceSensor);
  const int torque = mj_name2id(m, mjOBJ_SENSOR, phri::SimScene::kTorqueSensor);
  ASSERT_TRUE(phri::SiteWrenchSensor::reproduces(m, force, torque));
  EXPECT_FALSE(phri::SiteWrenchSensor::reproduces(m, torque, force));
  m->sensor_cutoff[force] = 100.0;
  EXPECT_FALSE(phri::SiteWrenchSensor::reproduces(m, force, torque));
  m->sensor_cutoff[force] = 0.0;
  // The tool's box and the floor collide, the floor raised into the box.
  const int tool_geom = mj_name2id(m, mjOBJ_GEOM, phri::SimScene::kToolGeom);
  const int floor = mj_name2id(m, mjOBJ_GEOM, phri::SimScene::kFloorGeom);
  ASSERT_GE(tool_geom, 0);
  ASSERT_GE(floor, 0);
  for (int g : {tool_geom, floor}) m->geom_contype[g] = m->geom_conaffinity[g] = 1;
  mjData* d = mj_makeData(m);
  mju_copy(d->qpos, robot.mujoco_data()->qpos, m->nq);
  mj_forward(m, d);
  m->geom_pos[3 * floor + 2] = d->geom_xpos[3 * tool_geom + 2] + 0.2 * m->geom_size[3 * tool_geom + 2];
  phri::SiteWrenchSensor readings(m, force, torque);
  phri::RandomGenerator rng(3);
  std::vector<double> qvel(static_cast<std::size_t>(m->nv));
  int tool_contacts = 0;
  for (int k = 0; k < 400; ++k) {
    for (int i = 0; i < m->nv; ++i) d->qvel[i] = rng.uniform(-1.0, 1.0);
    for (int i = 0; i < 6 * m->nbody; ++i) d->xfrc_applied[i] = k % 5 == 0 ? 0.0 : rng.uniform(-20.0, 20.0);
    mju_copy(qvel.data(), d->qvel, m->nv);
    if (k % 2 == 0) {
      mj_forward(m, d);
    } else {
      mj_step(m, d);  // its forward pass reads the sensors, then d->qvel advances
    }
    double f[3], t[3];
    readings.evaluate(m, d, qvel.data(), f, t);
    EXPECT_EQ(std::memcmp(f, d->sensordata + m->sensor_adr[force], sizeof f), 0) << k;
    EXPECT_EQ(std::memcmp(t, d->sensordata + m->sensor_adr[torque], sizeof t), 0) << k;
    for (int i = 0; i < d->ncon; ++i) tool_contacts += d->contact[i].geom1 == tool_geom || d->contact[i].geom2 == tool_geom;
  }
  EXPECT_EQ(d->warning[mjWARN_BADQACC].number, 0);
  EXPECT_GT(tool_contacts, 100);
  std::printf("F/T readings: 400 states, %d contacts of the tool, last force (%.3f, %.3f, %.3f) N\n", tool_contacts,
              d->sensordata[m->sensor_adr[force]], d->sensordata[m->sensor_adr[force] + 1],
              d->sensordata[m->sensor_adr[force] + 2]);
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST(SimRobotSensors, EncoderIsQuantised) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  const double quantum = 2.0 * M_PI / c.noise.encoder_counts_per_rev;
  const auto& s = robot.read();
  for (int i = 0; i < 7; ++i) {
    const double counts = s.q_rad[i] / quantum;
    EXPECT_NEAR(counts, std::round(counts), 1e-6);
    EXPECT_LE(std::abs(s.q_rad[i] - robot.truth().q_rad[i]), 0.5 * quantum + 1e-12);
  }
}

// ------------------------------------------------------------------------------ vendor modes
TEST(SimRobotVendorModes, PositionStepSettles) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kPosition;
  cmd.q_rad = to_vector(kTarget);
  const double step = 0.05;
  for (int j : {1, 3, 5}) cmd.q_rad[j] += step;
  robot.write(cmd);
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(7);
  for (int k = 0; k < 1500; ++k) {
    robot.read();
    peak = peak.cwiseMax(robot.truth().q_rad - cmd.q_rad);
  }
  const Eigen::VectorXd error = robot.truth().q_rad - cmd.q_rad;
  std::printf("position step 0.05 rad on joints 2, 4, 6: overshoot %.1f / %.1f / %.1f %%, error after 1.5 s %.1e rad\n",
              100 * peak[1] / step, 100 * peak[3] / step, 100 * peak[5] / step, error.cwiseAbs().maxCoeff());
  EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT(robot.truth().qd_rad_s.cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_GT(peak[1], 0.0);           // some overshoot (industrial-like, underdamped on the big joints)
  EXPECT_LT(peak[1], 0.4 * step);    // but not oscillatory
}

// Joint 1 spun by a constant external moment under the vendor torque loops; the steady speed has
// a closed form per mode (b viscous, Fc Coulomb, tau_e the external moment, tau_d = 0 on joint 1):
//   Current (i = 0)       : b qd = tau_e - Fc
//   KinovaTorque          : (B + b) qd = (1 + Kt) tau_e - Fc      (tau_m = -Kt tau_s - B qd)
//   KinovaTorqueHighVel.  : b qd = 2 tau_e - Fc                    (H(1) = 1: tau_m = -tau_s)
double spin_speed(LowLevelMode mode, double tau_e, double seconds, double joint1_torque_constant_scale = 1.0) {
  SimRobotConfig c = load(false);
  if (joint1_torque_constant_scale != 1.0) {
    SimRobotConfig::ActuatorOverride o;
    o.joint = c.actuators[0].joint_name;
    o.torque_constant_scale = joint1_torque_constant_scale;
    c.actuator_overrides.push_back(o);
  }
  phri::ExternalForce f;
  f.body = "shoulder_link";  // its z axis is joint 1's axis
  f.frame = phri::ExternalForce::Frame::kLocal;
  f.torque_Nm = Eigen::Vector3d(0, 0, tau_e);
  f.profile = phri::ExternalForce::Profile::kStep;
  f.start_s = 0.0;
  f.duration_s = 100.0;
  c.disturbances.push_back(f);
  SimRobot robot(c);
  Reference ref(c);
  RobotCommand cmd(7);
  cmd.mode = mode;
  const mjData* d = robot.mujoco_data();
  const Eigen::VectorXd g0 = ref.gravity(to_vector(kTarget));
  for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) {
    // Other joints: exact gravity and velocity terms (MuJoCo's bias forces); joint 1: nothing.
    for (int i = 0; i < 7; ++i) cmd.tau_Nm[i] = i == 0 ? 0.0 : d->qfrc_bias[i];
    cmd.current_A = currents_for(robot, g0);
    cmd.current_A[0] = 0.0;
    EXPECT_EQ(robot.write(cmd), WriteStatus::kOk);
    robot.read();
  }
  return robot.truth().qd_rad_s[0];
}

TEST(SimRobotVendorModes, TorqueLoopsClosedFormSpeeds) {
  const SimRobotConfig c = load(false);
  const double tau_e = 3.0;
  const double fc = c.actuators[0].friction.coulomb_Nm;
  const double b = c.actuators[0].friction.viscous_Nms_per_rad;
  const double kt = c.vendor.torque_feedback_gain[0];
  const double damping = c.vendor.torque_velocity_damping_Nms_per_rad[0];
  const double current = spin_speed(LowLevelMode::kCurrent, tau_e, 4.0);
  const double torque = spin_speed(LowLevelMode::kKinovaTorque, tau_e, 2.0);
  const double high = spin_speed(LowLevelMode::kKinovaTorqueHighVelocity, tau_e, 6.0);
  const double e_current = (tau_e - fc) / b;
  const double e_torque = ((1 + kt) * tau_e - fc) / (damping + b);
  const double e_high = (2 * tau_e - fc) / b;
  std::printf("joint 1 under a %.1f N.m moment, steady speed (rad/s): current %.4f (%.4f), kinova_torque %.4f "
              "(%.4f), high_velocity %.4f (%.4f)\n", tau_e, current, e_current, torque, e_torque, high, e_high);
  EXPECT_NEAR(current, e_current, 0.02 * e_current);
  EXPECT_NEAR(torque, e_torque, 0.02 * e_torque);
  EXPECT_NEAR(high, e_high, 0.02 * e_high);
}

// The vendor's firmware converts torque to current with its stored (nominal) K_T G_r; a drive whose
// true constant is k x nominal delivers k x what the loop asks. Closed forms as above with k:
//   KinovaTorque          : (k B + b) qd = (1 + k Kt) tau_e - Fc
//   KinovaTorqueHighVel.  : b qd = (1 + k) tau_e - Fc
TEST(SimRobotVendorModes, VendorLoopsConvertWithTheNominalTorqueConstant) {
  const SimRobotConfig c = load(false);
  const double tau_e = 3.0, k = 0.8;
  const double fc = c.actuators[0].friction.coulomb_Nm;
  const double b = c.actuators[0].friction.viscous_Nms_per_rad;
  const double kt = c.vendor.torque_feedback_gain[0];
  const double damping = c.vendor.torque_velocity_damping_Nms_per_rad[0];
  const double torque = spin_speed(LowLevelMode::kKinovaTorque, tau_e, 2.0, k);
  const double high = spin_speed(LowLevelMode::kKinovaTorqueHighVelocity, tau_e, 6.0, k);
  const double e_torque = ((1 + k * kt) * tau_e - fc) / (k * damping + b);
  const double e_high = ((1 + k) * tau_e - fc) / b;
  std::printf("joint 1, K_T x %.2f, steady speed (rad/s): kinova_torque %.4f (%.4f), high_velocity %.4f (%.4f)\n", k,
              torque, e_torque, high, e_high);
  EXPECT_NEAR(torque, e_torque, 0.02 * e_torque);
  EXPECT_NEAR(high, e_high, 0.02 * e_high);
}

// Position mode starts at the exact holding torque even when the drives' true K_T differs from
// the firmware's: the servo's integrator is set in the firmware's units.
TEST(SimRobotVendorModes, PositionHoldStartsStillWithDriveGainError) {
  SimRobotConfig c = load(false);
  for (const auto& a : c.actuators.joints()) {
    SimRobotConfig::ActuatorOverride o;
    o.joint = a.joint_name;
    o.torque_constant_scale = 0.85;
    c.actuator_overrides.push_back(o);
  }
  SimRobot robot(c);
  double drift = 0.0;
  for (int k = 0; k < 500; ++k) {
    robot.read();
    drift = std::max(drift, (robot.truth().q_rad - to_vector(kTarget)).cwiseAbs().maxCoeff());
  }
  std::printf("position hold with K_T x 0.85: largest joint drift over 0.5 s %.2e rad\n", drift);
  EXPECT_LT(drift, 1e-5);
}

// ------------------------------------------------------------------------------- disturbances
TEST(SimRobotDisturbances, ForcesOnTheToolShowInTheFtSensor) {
  SimRobotConfig c = load(false);
  phri::ExternalForce world;
  world.body = "tool";
  world.point_m = Eigen::Vector3d(0, 0, 0.05);
  world.frame = phri::ExternalForce::Frame::kWorld;
  world.force_N = Eigen::Vector3d(10, 0, 0);
  world.start_s = 0.2;
  world.duration_s = 0.6;
  phri::ExternalForce local = world;
  local.frame = phri::ExternalForce::Frame::kLocal;
  local.force_N = Eigen::Vector3d(0, 5, 0);
  local.start_s = 1.0;
  phri::ExternalForce link = world;
  link.body = "forearm_link";
  link.point_m = Eigen::Vector3d(0, -0.1, 0);
  link.force_N = Eigen::Vector3d(0, 20, 0);
  link.start_s = 1.8;
  c.disturbances = {world, local, link};
  SimRobot robot(c);
  Reference ref(c);
  const Eigen::Matrix3d R = ref.flange_rotation(to_vector(kTarget));
  // Mean F/T over 0.1 s ending at t, and the weight of the tool in the sensor axes of that moment.
  Eigen::Vector3d weight;
  auto wrench_at = [&](double t) {
    while (robot.state().time_s < t - 0.1 - 1e-9) robot.read();
    Eigen::Matrix<double, 6, 1> sum = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 100; ++k) {
      sum += robot.read().wrench_sensor;
      rotation += robot.truth().sensor_rotation / 100.0;
    }
    weight = rotation.transpose() * (c.tool.mass_kg * Eigen::Vector3d(0, 0, -9.81));
    return Eigen::Matrix<double, 6, 1>(sum / 100.0);
  };
  // World-frame push on the tool: the load on the sensor grows by the push, in sensor axes.
  const auto w1 = wrench_at(0.75);
  const Eigen::Vector3d f1 = R.transpose() * world.force_N;
  const Eigen::Vector3d r(0, 0, 0.05);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(w1[k], weight[k] + f1[k], 0.02) << k;
    EXPECT_NEAR(w1[3 + k], (c.tool.com_m.cross(weight) + r.cross(f1))[k], 0.002) << k;
  }
  // Local-frame push: exactly its components in the sensor frame (the tool frame is the sensor frame).
  const auto w2 = wrench_at(1.55);
  EXPECT_NEAR(w2[1] - weight[1], 5.0, 0.02);
  EXPECT_NEAR(w2[3] - c.tool.com_m.cross(weight)[0], -0.05 * 5.0, 0.002);
  // A push on the forearm does not load the sensor beyond the small motion it causes, and none
  // once the arm is back at rest.
  const auto w3 = wrench_at(2.35);
  EXPECT_NEAR((w3.head<3>() - weight).norm(), 0.0, 0.2);
  const auto w4 = wrench_at(3.6);
  EXPECT_NEAR((w4.head<3>() - weight).norm(), 0.0, 0.01);
}

TEST(SimRobotDisturbances, RandomPushesHappenWithinTheirBounds) {
  SimRobotConfig c = load();
  c.random_pushes.enabled = true;
  c.random_pushes.start_s = 0.1;
  c.random_pushes.min_interval_s = 0.2;
  c.random_pushes.max_interval_s = 0.5;
  SimRobot robot(c);
  std::uint32_t seen = 0;
  double peak_speed = 0.0;
  for (int k = 0; k < 3000; ++k) {
    robot.read();
    const auto& p = robot.truth().last_push;
    if (p.index > seen) {
      seen = p.index;
      EXPECT_LE(p.peak_force_N, c.random_pushes.max_force_N);
      EXPECT_GE(p.peak_force_N, c.random_pushes.min_force_N);
    }
    peak_speed = std::max(peak_speed, robot.truth().qd_rad_s.cwiseAbs().maxCoeff());
  }
  EXPECT_GE(seen, 3u);
  EXPECT_GT(peak_speed, 1e-3);  // the arm felt them
  EXPECT_FALSE(robot.state().fault);
}

// ------------------------------------------------------------------------------ model mismatch
TEST(SimRobotMismatch, DriveGainErrorIsDrawnWithinItsBoundDeterministically) {
  SimRobotConfig c = load(false);
  c.mismatch.torque_constant_fraction = 0.2;
  const phri::ActuatorTable off = c.plant_actuators();  // mismatch disabled: nominal
  c.mismatch.enabled = true;
  const phri::ActuatorTable a = c.plant_actuators(), b = c.plant_actuators();
  c.mismatch.seed += 1;
  const phri::ActuatorTable other = c.plant_actuators();
  int distinct = 0;
  for (int i = 0; i < a.size(); ++i) {
    const double nominal = c.actuators[i].torque_constant_Nm_per_A;
    EXPECT_EQ(off[i].torque_constant_Nm_per_A, nominal);
    const double ratio = a[i].torque_constant_Nm_per_A / nominal;
    EXPECT_GE(ratio, 0.8);
    EXPECT_LE(ratio, 1.2);
    EXPECT_EQ(a[i].torque_constant_Nm_per_A, b[i].torque_constant_Nm_per_A);
    distinct += a[i].torque_constant_Nm_per_A != other[i].torque_constant_Nm_per_A;
    EXPECT_EQ(a[i].friction.coulomb_Nm, c.actuators[i].friction.coulomb_Nm);  // only the gain changes
  }
  EXPECT_EQ(distinct, a.size());
}

TEST(SimRobotMismatch, PerturbsLinksDeterministicallyAndPhysically) {
  SimRobotConfig c = load(false);
  SimRobot nominal(c);
  c.mismatch.enabled = true;
  SimRobot a(c), b(c);
  c.mismatch.seed = 8;
  SimRobot other(c);
  const mjModel* m0 = nominal.mujoco_model();
  const mjModel* ma = a.mujoco_model();
  int changed = 0;
  for (int body = 2; body <= 8; ++body) {  // the seven moving links (0 world, 1 base_link)
    const double ratio = ma->body_mass[body] / m0->body_mass[body];
    EXPECT_LE(std::abs(ratio - 1.0), 0.05 + 1e-12);
    changed += ratio != 1.0;
    EXPECT_EQ(ma->body_mass[body], b.mujoco_model()->body_mass[body]);
    const double* I = ma->body_inertia + 3 * body;
    EXPECT_GE(I[0] + I[1], I[2]);
    EXPECT_GE(I[1] + I[2], I[0]);
    EXPECT_GE(I[0] + I[2], I[1]);
  }
  EXPECT_EQ(changed, 7);
  EXPECT_NE(ma->body_mass[3], other.mujoco_model()->body_mass[3]);
  // The controller's URDF gravity no longer matches the plant's.
  Reference ref(c);
  const Eigen::VectorXd g = ref.gravity(to_vector(kTarget));
  double diff = 0.0;
  for (int i = 0; i < 7; ++i) diff = std::max(diff, std::abs(a.mujoco_data()->qfrc_bias[i] - g[i]));
  EXPECT_GT(diff, 0.05);
}

// --------------------------------------------------------------------------- determinism
std::vector<double> record(const SimRobotConfig& c, int cycles) {
  SimRobot robot(c);
  RobotCommand cmd(7);
  std::vector<double> log;
  for (int k = 0; k < cycles; ++k) {
    const auto& s = robot.read();
    // A PD in Current mode after 0.5 s, on the noisy measurements (so noise feeds back).
    if (k == 500) cmd.mode = LowLevelMode::kCurrent;
    if (cmd.mode == LowLevelMode::kCurrent) {
      for (int i = 0; i < 7; ++i) {
        const double tau = 200.0 * (kTarget[static_cast<std::size_t>(i)] - s.q_rad[i]) - 10.0 * s.qd_rad_s[i] +
                           robot.mujoco_data()->qfrc_bias[i];
        cmd.current_A[i] = std::clamp(tau / robot.plant_actuators()[i].torque_per_amp(), -5.0, 5.0);
      }
    } else {
      cmd.q_rad = to_vector(kTarget);
    }
    robot.write(cmd);
    for (const Eigen::VectorXd* v : {&s.q_rad, &s.qd_rad_s, &s.tau_sensor_Nm, &s.current_A}) {
      log.insert(log.end(), v->data(), v->data() + v->size());
    }
    log.insert(log.end(), s.wrench_sensor.data(), s.wrench_sensor.data() + 6);
    log.push_back(robot.truth().cable_force_N);
  }
  return log;
}

TEST(SimRobotDeterminism, SameSeedGivesBitIdenticalTrajectories) {
  SimRobotConfig c = load();
  c.mismatch.enabled = true;
  c.random_pushes.enabled = true;
  c.random_pushes.start_s = 0.2;
  c.drop_test.enabled = true;
  c.drop_test.release_time_s = 0.3;
  const auto a = record(c, 1500);
  const auto b = record(c, 1500);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
  c.seed = 2;
  const auto other = record(c, 1500);
  EXPECT_NE(std::memcmp(a.data(), other.data(), a.size() * sizeof(double)), 0);
  // reset() replays the same run.
  SimRobot robot(c);
  const Eigen::VectorXd first = robot.read().tau_sensor_Nm;
  for (int k = 0; k < 50; ++k) robot.read();
  robot.reset();
  EXPECT_EQ(robot.read().tau_sensor_Nm, first);
}

// ----------------------------------------------------------------------------- bad commands
TEST(SimRobotCommands, RefusesBadCommandsAndHoldsThePreviousOne) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  RobotCommand good(7);
  good.mode = LowLevelMode::kPosition;
  good.q_rad = to_vector(kTarget);
  good.q_rad[3] += 0.02;
  ASSERT_EQ(robot.write(good), WriteStatus::kOk);
  for (int k = 0; k < 100; ++k) robot.read();

  RobotCommand bad = good;
  bad.q_rad[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(robot.write(bad), WriteStatus::kNotFinite);
  EXPECT_EQ(robot.state().last_write_status, WriteStatus::kNotFinite);
  bad = good;
  bad.q_rad[1] = 2.5;  // beyond joint_2's 2.24 rad
  EXPECT_EQ(robot.write(bad), WriteStatus::kOutOfRange);
  bad = good;
  bad.mode = LowLevelMode::kKinovaTorque;
  bad.tau_Nm.setZero();
  bad.tau_Nm[5] = 60.0;  // small actuator: 52 N.m at most
  EXPECT_EQ(robot.write(bad), WriteStatus::kOutOfRange);
  bad.tau_Nm[5] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(robot.write(bad), WriteStatus::kNotFinite);
  bad.mode = LowLevelMode::kCurrent;
  bad.current_A.setZero();
  bad.current_A[0] = 20.0;  // 9.55 A limit
  EXPECT_EQ(robot.write(bad), WriteStatus::kOutOfRange);
  bad.current_A.resize(6);
  EXPECT_EQ(robot.write(bad), WriteStatus::kSizeMismatch);
  bad.mode = static_cast<LowLevelMode>(9);
  EXPECT_EQ(robot.write(bad), WriteStatus::kInvalidMode);

  const auto& s = robot.read();
  EXPECT_EQ(s.rejected_writes, 7u);
  EXPECT_EQ(s.last_write_status, WriteStatus::kInvalidMode);
  EXPECT_EQ(s.mode, LowLevelMode::kPosition);  // still executing the good command
  for (int k = 0; k < 900; ++k) robot.read();
  EXPECT_NEAR(robot.truth().q_rad[3], good.q_rad[3], 1e-4);
  const mjData* d = robot.mujoco_data();
  for (int i = 0; i < robot.mujoco_model()->nq; ++i) EXPECT_TRUE(std::isfinite(d->qpos[i]));
  for (int i = 0; i < robot.mujoco_model()->nv; ++i) EXPECT_TRUE(std::isfinite(d->qfrc_applied[i]));
  EXPECT_EQ(robot.write(good), WriteStatus::kOk);
  EXPECT_EQ(robot.read().last_write_status, WriteStatus::kOk);
  EXPECT_FALSE(robot.state().fault);
}

TEST(SimRobotCommands, ModeChangesTakeEffectAtTheNextCycle) {
  const SimRobotConfig c = load();
  SimRobot robot(c);
  robot.read();
  RobotCommand cmd(7);
  cmd.mode = LowLevelMode::kKinovaTorqueHighVelocity;
  for (int i = 0; i < 7; ++i) cmd.tau_Nm[i] = robot.mujoco_data()->qfrc_bias[i];
  robot.write(cmd);
  EXPECT_EQ(robot.state().mode, LowLevelMode::kPosition);  // nothing changed yet
  EXPECT_EQ(robot.read().mode, LowLevelMode::kKinovaTorqueHighVelocity);
  // Switching with the exact holding torque is bumpless: the arm stays put.
  for (int k = 0; k < 500; ++k) robot.read();
  EXPECT_LT((robot.truth().q_rad - to_vector(kTarget)).cwiseAbs().maxCoeff(), 1e-3);
  cmd.mode = LowLevelMode::kPosition;
  cmd.q_rad = robot.state().q_rad;
  robot.write(cmd);
  for (int k = 0; k < 500; ++k) robot.read();
  EXPECT_LT((robot.truth().q_rad - cmd.q_rad).cwiseAbs().maxCoeff(), 1e-3);
}

// ---------------------------------------------------------------------------- no allocation
TEST(SimRobotRealTime, ReadAndWriteDoNotAllocate) {
  SimRobotConfig c = load();
  c.drop_test.enabled = true;
  c.drop_test.release_time_s = 0.1;
  c.random_pushes.enabled = true;
  c.random_pushes.start_s = 0.05;
  phri::ExternalForce f;
  f.body = "forearm_link";
  f.force_N = Eigen::Vector3d(0, 5, 0);
  f.profile = phri::ExternalForce::Profile::kHalfSine;
  f.duration_s = 1.0;
  c.disturbances.push_back(f);
  SimRobot robot(c);
  RobotCommand cmd(7);
  cmd.q_rad = to_vector(kTarget);
  robot.write(cmd);
  robot.read();
  const LowLevelMode modes[] = {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque,
                                LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kCurrent};
  std::size_t allocations = 0;
  {
    phri::test::AllocationCounter count;
    phri::test::NoMallocScope no_malloc;
    for (LowLevelMode mode : modes) {
      cmd.mode = mode;
      for (int k = 0; k < 100; ++k) {
        for (int i = 0; i < 7; ++i) {
          cmd.tau_Nm[i] = robot.mujoco_data()->qfrc_bias[i];
          cmd.current_A[i] = cmd.tau_Nm[i] / robot.plant_actuators()[i].torque_per_amp();
        }
        robot.write(cmd);
        robot.read();
      }
    }
    cmd.q_rad[0] = std::numeric_limits<double>::quiet_NaN();
    cmd.mode = LowLevelMode::kPosition;
    robot.write(cmd);  // refused, still no allocation
    robot.read();
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0u);
}

// ------------------------------------------------------------------------------------ clock
TEST(LoopClock, LockstepAndRealTimePacing) {
  phri::LoopClock lockstep(0.001, phri::LoopClock::Pacing::kLockstep);
  for (int k = 0; k < 1000; ++k) EXPECT_EQ(lockstep.wait_next(), 0.0);
  EXPECT_EQ(lockstep.cycles(), 1000u);
  EXPECT_EQ(lockstep.overruns(), 0u);
  // Real time: N cycles cannot end before N - 1 periods (sleep_until never wakes early).
  phri::LoopClock real(0.002, phri::LoopClock::Pacing::kRealTime);
  const auto start = std::chrono::steady_clock::now();
  real.start();
  for (int k = 0; k < 10; ++k) real.wait_next();
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(elapsed, 9 * 0.002);
  EXPECT_EQ(real.cycles(), 10u);
}

}  // namespace
