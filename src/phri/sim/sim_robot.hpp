#pragma once
// phri::SimRobot: the simulated Kinova Gen3 behind phri::RobotInterface — MuJoCo 2.2.2 rigid-body
// physics plus what makes a torque-controlled arm hard to control: the drives (current
// saturation, reflected rotor inertia, Coulomb/viscous/static joint friction), the vendor's own
// actuator loops (KinovaDriveEmulator, or GenericDrive for `drive: generic`), realistic sensors, model mismatch and disturbances.
//
//   phri::SimRobot robot(phri::SimRobotConfig::from_yaml_file("configs/plant_gen3.yaml"));
//   phri::LoopClock clock(robot.period_s(), phri::LoopClock::Pacing::kLockstep);  // or kRealTime
//   phri::RobotCommand cmd(robot.dof());
//   for (int k = 0; k < 5000; ++k) {
//     const phri::RobotState& s = robot.read();   // advances the physics by one control period
//     cmd.mode = phri::LowLevelMode::kCurrent;
//     cmd.current_A = ...;                        // from s
//     robot.write(cmd);                           // takes effect at the next read()
//     clock.wait_next();
//   }
//
// Lockstep: read() runs config.substeps_per_cycle() physics steps (4 at 4 kHz / 1 kHz) on the
// command in force, then returns the new state; the wall-clock pace is the caller's (LoopClock).
// Before the first write() the arm holds its initial pose in Position mode.
//
// One physics step (period dt):
//   1. MuJoCo's position/velocity stage (mj_step1) on the current state;
//   2. the drives' sensors (encoder quantisation; velocity and torque noise) and the vendor loop
//      of the running mode give the motor current i, saturated at the drive limit;
//   3. joint torque on the motor side: tau_m = K_T G_r i, viscous friction -b qd, and dry
//      friction from StickSlipFriction (static level at rest, Coulomb level when sliding: a joint
//      at rest sticks until the net torque exceeds the static level); the viscous and presliding
//      dampers go through MuJoCo's joint damping (implicit in its Euler step); the reflected rotor
//      inertia is MuJoCo's joint armature;
//   4. external forces: scripted timeline, random pushes, the drop test's latch and cable;
//   5. MuJoCo step (semi-implicit Euler); then the joint torque sensor value
//        tau_s = tau_m - b qd + f_dry - I_r qdd      (qd, qdd: the step's new velocity, (v1 - v0)/dt)
//      i.e. the torque transmitted between the
//      drive output and the link, with friction and rotor inertia on the motor side;
//   6. at the F/T rate, MuJoCo's force/torque sensor at the tool origin (the interaction between the
//      tool body and the adapter body it is welded to), as MuJoCo's sensor stage of that step
//      would read it (SiteWrenchSensor: the same numbers for the tool alone).
// Sensor values reach the vendor loops one physics step later (the sampling delay).
//
// No allocation and no exception inside read() and write(); refused commands are statuses.
// A divergence of the physics (MuJoCo reports bad accelerations) latches RobotState::fault.
#include <phri/core/random_generator.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/sim/drive_loops.hpp>
#include <phri/sim/elastic_transmission.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/random_push_generator.hpp>
#include <phri/sim/body_region_surrogate.hpp>
#include <phri/sim/site_wrench_sensor.hpp>
#include <phri/robot/ground_truth.hpp>
#include <phri/robot/push_input.hpp>
#include <phri/robot/robot_interface.hpp>
#include <phri/config/sim_robot_config.hpp>
#include <phri/sim/stick_slip_friction.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace phri {

class SimRobot final : public RobotInterface, public PushInput, public GroundTruth {
public:
  using Vector6d = Eigen::Matrix<double, 6, 1>;

  /// Noise-free plant quantities no real sensor gives, for tests, logs and experiments.
  struct Truth {
    double time_s = 0.0;
    Eigen::VectorXd q_rad, qd_rad_s, qdd_rad_s2;  ///< qdd: of the last physics step
    Eigen::VectorXd q_motor_rad;  ///< rotor angle / G_r (elastic joints); = q_rad with a rigid transmission
    Eigen::VectorXd current_A;                     ///< applied (saturated) motor current
    Eigen::VectorXd tau_motor_Nm;                  ///< K_T G_r i
    Eigen::VectorXd tau_friction_Nm;               ///< friction acting on the joint (viscous + dry), opposing motion
    Eigen::VectorXd tau_transmitted_Nm;            ///< what the torque sensor measures, without noise/offset
    Vector6d wrench_sensor = Vector6d::Zero();     ///< F/T at its last sample, without noise/bias
    Eigen::Vector3d sensor_position_m = Eigen::Vector3d::Zero();  ///< F/T frame origin in the world
    Eigen::Matrix3d sensor_rotation = Eigen::Matrix3d::Identity(); ///< F/T frame axes in the world
    // drop test
    bool drop_released = false;
    Eigen::Vector3d drop_mass_position_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d drop_mass_velocity_m_s = Eigen::Vector3d::Zero();
    double cable_length_m = 0.0;  ///< anchor to mass centre
    double cable_force_N = 0.0;   ///< cable tension (0 while slack)
    // floor (a table when the tool touches it)
    double floor_normal_force_N = 0.0;  ///< the floor's normal force on the robot's geoms, summed
    // a body region in the way (SimRobotConfig::surrogate)
    double surrogate_force_N = 0.0;       ///< on the tool, along the face's normal, at the cycle's last physics step
    double surrogate_peak_force_N = 0.0;  ///< the largest over the cycle's physics steps
    double surrogate_compression_m = 0.0; ///< of its spring while touched (0 otherwise)
    double surrogate_displacement_m = 0.0;  ///< how far its mass has recoiled
    // random pushes
    RandomPushGenerator::Push last_push;  ///< latest push drawn (index 0: none yet)
  };

  explicit SimRobot(const SimRobotConfig& config);
  ~SimRobot() override;

  int dof() const override { return n_; }
  double period_s() const override { return config_.control_period_s; }
  const RobotState& read() override;
  WriteStatus write(const RobotCommand& command) override;

  /// The latest state, without advancing (after construction: the initial state).
  const RobotState& state() const { return state_; }
  const Truth& truth() const { return truth_; }
  const SimRobotConfig& config() const { return config_; }
  /// The drives as simulated (actuators.yaml with the plant overrides).
  const ActuatorTable& plant_actuators() const { return plant_actuators_; }
  /// Joint i's dry friction as the plant applies it (levels, presliding, sliding form): ground truth.
  const StickSlipFriction::Parameters& dry_friction_parameters(int i) const;
  /// Position limits used to validate kPosition set-points (+-100 rad for continuous joints).
  const Eigen::VectorXd& position_lower_rad() const { return lower_; }
  const Eigen::VectorXd& position_upper_rad() const { return upper_; }
  /// The drives' own loops (config().drive: Kinova's, emulated, or a generic drive's).
  const DriveLoops& drive() const { return *drive_; }
  /// Back to the initial state: same configuration and seeds, so the same run again (the live
  /// disturbance cleared).
  void reset();

  /// The scene's body named `name`, for set_live_disturbance; -1 when there is none (or the world).
  int body_id(const std::string& name) const;
  /// One disturbance on top of config().disturbances, chosen while the simulation runs (an
  /// experiment that starts each push when the arm has settled from the previous one): `force`
  /// (its `body` name is not read) on body `body` (body_id), from the next read() on, following
  /// its profile over its start_s and duration_s. Replaces the previous one; body -1 clears it.
  /// No allocation.
  void set_live_disturbance(int body, const ExternalForce& force);

  /// Moves the body region (config().surrogate, enabled) so that its face at rest is at `face`
  /// with the outward unit `normal` (world), at rest and untouched; an experiment places it on the
  /// arm's path once it knows the path. No allocation.
  void set_surrogate_face(const Eigen::Vector3d& face, const Eigen::Vector3d& normal);

  /// The point on the tool box's centre line along `direction` (world, unit) as far out as the box
  /// reaches: a body region's face square to `direction` placed there just touches the box. Needs
  /// config().surrogate enabled (zero otherwise).
  Eigen::Vector3d tool_point_along(const Eigen::Vector3d& direction) const;
  /// The tool box centre's true velocity (world) [m/s]. Needs config().surrogate enabled (zero otherwise).
  Eigen::Vector3d tool_velocity() const;

  // ---- PushInput: a step force as a live disturbance from the latest state's time on.
  int push_target(const std::string& link) const override { return body_id(link); }
  void push(int target, const Eigen::Vector3d& point_m, const Eigen::Vector3d& force_world_N, double hold_s) override;

  // ---- GroundTruth: truth().q_rad, the link side of the joints.
  const Eigen::VectorXd& true_joint_positions() const override { return truth_.q_rad; }
  const Eigen::VectorXd& true_joint_velocities() const override { return truth_.qd_rad_s; }

  /// Each arm joint's diagonal of the plant's joint-space inertia M_ii at the current posture
  /// (MuJoCo's qM of the last step: the true, mismatched inertials and any payload). With elastic
  /// joints the rotor is off the link, so this is the link side alone; rigid: armature included.
  Eigen::VectorXd joint_inertia_diagonal() const;

  /// MuJoCo model and data, read-only (viewers, tests comparing with MuJoCo's own quantities). The
  /// cycle runs without MuJoCo's sensor stage: sensordata, cacc and cfrc_* keep their values of the
  /// initial F/T sample (the cycle's samples are in truth().wrench_sensor).
  const mjModel_* mujoco_model() const { return m_.get(); }
  const mjData_* mujoco_data() const { return d_.get(); }
  /// MJCF text of the scene that was loaded.
  const std::string& scene_mjcf() const { return scene_xml_; }

private:
  // construction, in this order: the model's options, the arm's joints (their drive constants
  // written into the model), the link mismatch, the scene objects, then the data and the buffers
  void set_physics_options();
  void place_base();
  std::vector<int> bind_arm_joints();  // returns the joints' bodies, in the order of actuators.yaml
  int bind_joint(int i);               // returns the joint's body
  void bind_elastic(int i);
  void perturb_link_inertials(const std::vector<int>& arm_bodies);
  void find_ft_sensor();
  void find_drop_test();
  void find_surrogate();
  void find_disturbance_bodies();
  void find_push_links(const std::vector<int>& arm_bodies);
  void make_data();
  void set_generic_hold_gains();
  void allocate_buffers();
  // reset(), in this order
  void restart_noise_and_counters();
  Eigen::Vector3d place_initial_pose();  // returns the drop mass's weight (zero without a drop test)
  Eigen::VectorXd holding_torque(const Eigen::Vector3d& drop_force_on_tool) const;
  void start_drives_holding(const Eigen::VectorXd& hold);
  void take_initial_ft_sample(const Eigen::VectorXd& hold);

  // The F/T sample from MuJoCo's sensor readings (force, torque: site frame, on the tool).
  void sample_ft_sensor(const double* force, const double* torque);
  void substep(bool last_of_period);
  // Step 1 and 5 of substep() per transmission: rigid (friction and rotor inertia on the link) or
  // elastic (ElasticTransmission: the link feels the spring only).
  void prepare_rigid();
  void finish_rigid();
  void prepare_elastic();
  void finish_elastic();
  bool elastic() const { return !elastic_.empty(); }
  // What the vendor position servo's encoder reads (motor or link side) [rad, rad/s].
  double servo_position(int i) const;
  double servo_velocity(int i) const;
  void apply_external_forces(double t);
  void apply_force(int body, const Eigen::Vector3d& point_local, bool local_frame, const Eigen::Vector3d& force,
                   const Eigen::Vector3d& torque);
  void apply_drop_forces(double t);
  void apply_surrogate_force();
  void sample_state();
  // The motor torque as the vendor firmware believes it: the drive current times its stored
  // (nominal, actuators.yaml) K_T G_r. It differs from tau_motor_ when the plant's torque
  // constant is off (actuator_overrides, mismatch.torque_constant_fraction): the firmware
  // cannot know the true one, so its loops convert torque to current with the nominal value.
  const Eigen::VectorXd& vendor_torque();
  WriteStatus validate(const RobotCommand& command) const;
  double quantize(double q) const;

  SimRobotConfig config_;
  ActuatorTable plant_actuators_;
  int n_ = 0;
  int substeps_ = 1;
  int filter_decimation_ = 1;
  int ft_decimation_ = 1;
  std::string scene_xml_;
  MjModelPtr m_;
  MjDataPtr d_;  // after m_: deleted before the model

  // joint addressing and drive/friction constants (plant side)
  std::vector<int> qadr_, dadr_;
  Eigen::VectorXd lower_, upper_, torque_per_amp_, current_limit_, max_torque_, armature_;
  Eigen::VectorXd nominal_torque_per_amp_, vendor_torque_;
  Eigen::VectorXd viscous_, offsets_;
  std::vector<StickSlipFriction> dry_;
  std::vector<ElasticTransmission> elastic_;  // empty: rigid transmission
  Eigen::VectorXd q_before_;                  // link angles at a physics step's start
  double quantum_ = 0.0;
  bool motor_encoder_ = false;  // the vendor servo's encoder is on the rotor (elastic joints, motor side)
  bool compensate_deflection_ = false;  // ... less the deflection its torque sensor measures
  double deflection_alpha_ = 1.0;       // that torque's low-pass step per physics step

  std::unique_ptr<DriveLoops> drive_;  // made at reset() (not in the cycle)
  std::vector<double> hold_kp_, hold_kd_;  // drive generic: the position hold's gains (set_generic_hold_gains)
  RobotCommand command_, pending_;
  bool has_pending_ = false;
  bool fault_ = false;
  int filter_phase_ = 0;  // physics steps since the reset, modulo filter_decimation_
  int ft_phase_ = 0;      // and modulo ft_decimation_
  // What the running mode's loop reads (DriveLoops::uses_*), for the period's steps.
  bool drive_reads_position_ = false, drive_reads_velocity_ = false, drive_reads_torque_ = false;

  // per-step buffers
  Eigen::VectorXd q_meas_, qd_meas_, tau_meas_, current_, tau_motor_, tau_viscous_, tau_dry_, tau_s_, deflection_torque_;
  Eigen::VectorXd hold_damping_;  // the drive's damping applied within the step (DriveLoops::implicit_damping)
  Eigen::VectorXd v_before_, f_dry_, damping_, qdd_;
  Vector6d wrench_true_ = Vector6d::Zero();
  Vector6d wrench_meas_ = Vector6d::Zero();
  std::uint32_t wrench_sequence_ = 0;
  double wrench_stamp_ = 0.0;

  RandomGenerator joint_noise_, ft_noise_;
  std::vector<double> noise_draws_;  // up to 3 standard normals per joint, drawn at once (fill_normal)
  RandomPushGenerator pushes_;
  std::vector<RandomPushGenerator::LinkSurface> push_links_;

  // scene objects
  int tool_body_ = -1;
  int sensor_site_ = -1;
  int force_adr_ = -1, torque_adr_ = -1;
  SiteWrenchSensor ft_readings_;  // bound: MuJoCo's F/T readings without its sensor stage (all bodies)
  std::vector<double> ft_qvel_;   // the velocities of an F/T step's forward pass (mj_step2 advances qvel)
  int anchor_site_ = -1;
  int drop_body_ = -1, drop_qadr_ = -1, drop_dadr_ = -1;
  int floor_geom_ = -1;
  int tool_geom_ = -1;  // the box the surrogate meets
  BodyRegionSurrogate surrogate_;
  double surrogate_peak_ = 0.0;  // over the cycle's physics steps
  double floor_normal_force() const;
  double latch_damping_ = 0.0;
  Eigen::Vector3d release_offset_ = Eigen::Vector3d::Zero();  // world axes, drawn at reset()
  Eigen::Vector3d hand_point_ = Eigen::Vector3d::Zero();      // held_by_hand: where the hand holds it
  std::vector<int> disturbance_bodies_;
  int live_body_ = -1;        // set_live_disturbance
  ExternalForce live_force_;  // its body name unused

  RobotState state_;
  Truth truth_;
};

}  // namespace phri
