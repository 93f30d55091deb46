#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/generic_drive.hpp>
#include <phri/sim/kinova_drive_emulator.hpp>
#include <phri/sim/link_inertial.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/sim_scene.hpp>

#include <Eigen/Geometry>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstring>
#include <memory>

namespace phri {
namespace {

// MuJoCo's force sensor gives the force the child body (the tool) receives from its parent (the
// adapter), in the site frame. The F/T sensor reports the opposite, the load the tool puts on the
// flange side (RobotState's convention: a hanging tool reads its weight). Checked by the test
// SimRobotSensors.FtSensorReadsToolWeight against m * g in the sensor frame.
constexpr double kWrenchSign = -1.0;


// Stream ids of RandomGenerator, one per noise source.
constexpr std::uint64_t kJointNoiseStream = 1;
constexpr std::uint64_t kFtNoiseStream = 2;
constexpr std::uint64_t kMismatchStream = 3;
constexpr std::uint64_t kReleaseStream = 4;

SimRobotConfig completed(SimRobotConfig config) {
  config.fill_defaults();
  config.validate();
  return config;
}

MjModelPtr load_scene(const std::string& xml, const std::string& source) {
  if (is_blank(xml)) throw ConfigError(source, "scene", "the composed scene is empty");  // MuJoCo would exit
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  const char* name = "phri_scene.xml";
  if (mj_makeEmptyFileVFS(&vfs, name, static_cast<int>(xml.size())) != 0) {
    throw ConfigError(source, "", "MuJoCo virtual file system is full");
  }
  const int index = mj_findFileVFS(&vfs, name);
  std::memcpy(vfs.filedata[index], xml.data(), xml.size());
  char error[1024] = "";
  MjModelPtr m(mj_loadXML(name, &vfs, error, sizeof(error)));
  mj_deleteVFS(&vfs);
  if (!m) throw ConfigError(source, "scene", "MuJoCo cannot load the composed scene: " + mujoco_error_line(error));
  return m;
}

Eigen::Matrix3d rotation(const mjtNum* xmat) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = xmat[3 * i + j];
  }
  return r;
}

// The body's first capsule geom, -1 if it has none.
int first_capsule(const mjModel* m, int body) {
  for (int g = m->body_geomadr[body]; g >= 0 && g < m->body_geomadr[body] + m->body_geomnum[body]; ++g) {
    if (m->geom_type[g] == mjGEOM_CAPSULE) return g;
  }
  return -1;
}

// The segment and radius of a capsule geom, in its body's frame: where random pushes land.
RandomPushGenerator::LinkSurface capsule_surface(const mjModel* m, int body, int capsule) {
  RandomPushGenerator::LinkSurface s;
  s.body = body;
  s.radius = m->geom_size[3 * capsule];
  const double half = m->geom_size[3 * capsule + 1];
  // Capsule axis = the geom's local z, placed by geom_pos / geom_quat in the body frame.
  mjtNum axis[3];
  const mjtNum z[3] = {0.0, 0.0, half};
  mju_rotVecQuat(axis, z, m->geom_quat + 4 * capsule);
  const Eigen::Vector3d c(m->geom_pos[3 * capsule], m->geom_pos[3 * capsule + 1], m->geom_pos[3 * capsule + 2]);
  const Eigen::Vector3d a(axis[0], axis[1], axis[2]);
  s.p0 = c - a;
  s.p1 = c + a;
  return s;
}

// The drives' own loops, fresh (no mode entered yet); `hold_kp`, `hold_kd`: a generic drive's gains.
std::unique_ptr<DriveLoops> make_drive_loops(const SimRobotConfig& c, const std::vector<double>& hold_kp,
                                             const std::vector<double>& hold_kd) {
  switch (c.drive) {
    case DriveKind::kGeneric:
      return std::make_unique<GenericDrive>(c.actuators, hold_kp, hold_kd, c.control_period_s);
    case DriveKind::kKinova:
      break;
  }
  return std::make_unique<KinovaDriveEmulator>(c.actuators, c.vendor, c.physics_step_s(), c.control_period_s);
}

// A plant drive's dry friction: its levels, the presliding spring-damper for the physics step, and the
// plant's sliding form (off by default).
StickSlipFriction::Parameters dry_friction(const SimRobotConfig& c, const ActuatorParameters& a) {
  StickSlipFriction::Parameters p = StickSlipFriction::presliding(a.friction.coulomb_Nm, a.friction.static_Nm,
                                                                   a.reflected_inertia_kgm2, c.physics_step_s(),
                                                                   c.friction.breakaway_velocity_rad_s);
  p.stribeck_velocity_rad_s = c.friction.stribeck_velocity_rad_s;
  p.stribeck_exponent = c.friction.stribeck_exponent;
  p.ripple_Nm = c.friction.ripple_fraction * a.friction.coulomb_Nm;
  p.ripple_cycles_per_rev = c.friction.ripple_cycles_per_rev;
  p.ripple_phase_rad = c.friction.ripple_phase_rad;
  return p;
}

}  // namespace

SimRobot::SimRobot(const SimRobotConfig& config)
    : config_(completed(config)),
      plant_actuators_(config_.plant_actuators()),
      n_(config_.dof()),
      drive_(make_drive_loops(config_, {}, {})) {
  substeps_ = config_.substeps_per_cycle();
  using Encoder = SimRobotConfig::Elasticity::Encoder;
  motor_encoder_ = config_.elasticity.enabled && config_.elasticity.position_loop_encoder != Encoder::kLink;
  compensate_deflection_ =
      config_.elasticity.enabled && config_.elasticity.position_loop_encoder == Encoder::kMotorCompensated;
  deflection_alpha_ = config_.physics_step_s() / (config_.elasticity.deflection_filter_s + config_.physics_step_s());
  filter_decimation_ = static_cast<int>(std::lround(config_.physics_rate_Hz / config_.vendor.high_velocity_rate_Hz));
  ft_decimation_ = static_cast<int>(std::lround(config_.physics_rate_Hz / config_.ft_sensor.rate_Hz));

  scene_xml_ = SimScene::build_mjcf(config_);
  m_ = load_scene(scene_xml_, config_.arm_file());
  set_physics_options();
  place_base();
  const std::vector<int> arm_bodies = bind_arm_joints();
  if (config_.mismatch.enabled) perturb_link_inertials(arm_bodies);
  find_ft_sensor();
  if (config_.drop_test.enabled) find_drop_test();
  if (config_.surrogate.enabled) find_surrogate();
  find_disturbance_bodies();
  if (config_.random_pushes.enabled) find_push_links(arm_bodies);
  make_data();
  if (config_.drive == DriveKind::kGeneric) set_generic_hold_gains();
  allocate_buffers();
  reset();
}

SimRobot::~SimRobot() = default;

void SimRobot::set_physics_options() {
  m_->opt.timestep = config_.physics_step_s();
  for (int k = 0; k < 3; ++k) m_->opt.gravity[k] = config_.gravity_m_s2[k];
  m_->opt.integrator = mjINT_EULER;
  m_->opt.disableflags |= mjDSBL_SENSOR;  // enabled only on F/T sampling steps
  if (!config_.floor.enabled) m_->opt.disableflags |= mjDSBL_CONTACT;
}

// The arm's root bodies (the world's children but the drop mass, which starts where the tool is)
// moved as one so that the base body lands at config.base_placement: by placement x P^-1, P the
// base's pose in the arm's own description (the identity when the base is an unplaced root, as
// the URDF's root link and the Gen3's base_link are). Left untouched when that is the identity.
void SimRobot::place_base() {
  Eigen::Isometry3d base_in_arm = Eigen::Isometry3d::Identity();
  if (!config_.base_link.empty()) {
    const int base = mj_name2id(m_.get(), mjOBJ_BODY, config_.base_link.c_str());
    if (base < 0) throw ConfigError(config_.source, "base_link", "no body '" + config_.base_link + "' in " + config_.arm_file());
    for (int b = base; b != 0; b = m_->body_parentid[b]) {
      if (m_->body_jntnum[b] > 0) {
        throw ConfigError(config_.source, "base_link",
                          std::string("body '") + mj_id2name(m_.get(), mjOBJ_BODY, b) + "' between the world and the base '" +
                              config_.base_link + "' has a joint in " + config_.arm_file() + ": the base must be fixed in the world");
      }
      Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
      body.translation() = Eigen::Vector3d(m_->body_pos[3 * b], m_->body_pos[3 * b + 1], m_->body_pos[3 * b + 2]);
      body.linear() = Eigen::Quaterniond(m_->body_quat[4 * b], m_->body_quat[4 * b + 1], m_->body_quat[4 * b + 2],
                                         m_->body_quat[4 * b + 3]).normalized().toRotationMatrix();
      base_in_arm = body * base_in_arm;
    }
  }
  const Eigen::Isometry3d move = config_.base_placement * base_in_arm.inverse();
  if (move.matrix() == Eigen::Matrix4d::Identity()) return;
  const Eigen::Quaterniond rotation(move.linear());
  const mjtNum q_move[4] = {rotation.w(), rotation.x(), rotation.y(), rotation.z()};
  const int drop = mj_name2id(m_.get(), mjOBJ_BODY, SimScene::kDropBody);
  for (int b = 1; b < m_->nbody; ++b) {
    if (m_->body_parentid[b] != 0 || b == drop) continue;
    const Eigen::Vector3d pos(m_->body_pos[3 * b], m_->body_pos[3 * b + 1], m_->body_pos[3 * b + 2]);
    const Eigen::Vector3d placed = move * pos;
    for (int k = 0; k < 3; ++k) m_->body_pos[3 * b + k] = placed[k];
    mjtNum quat[4];
    mju_mulQuat(quat, q_move, m_->body_quat + 4 * b);
    mju_normalize4(quat);
    for (int k = 0; k < 4; ++k) m_->body_quat[4 * b + k] = quat[k];
  }
}

std::vector<int> SimRobot::bind_arm_joints() {
  qadr_.resize(static_cast<std::size_t>(n_));
  dadr_.resize(static_cast<std::size_t>(n_));
  // Filled joint by joint in bind_joint().
  for (Eigen::VectorXd* v : {&lower_, &upper_, &torque_per_amp_, &nominal_torque_per_amp_, &current_limit_,
                             &max_torque_, &armature_, &viscous_, &offsets_}) {
    v->resize(n_);
  }
  vendor_torque_ = Eigen::VectorXd::Zero(n_);
  std::vector<int> arm_bodies;
  for (int i = 0; i < n_; ++i) arm_bodies.push_back(bind_joint(i));
  quantum_ = config_.noise.encoder_counts_per_rev > 0.0 ? 2.0 * std::numbers::pi / config_.noise.encoder_counts_per_rev
                                                         : 0.0;
  return arm_bodies;
}

int SimRobot::bind_joint(int i) {
  const ActuatorParameters& a = plant_actuators_[i];
  const int j = mj_name2id(m_.get(), mjOBJ_JOINT, a.joint_name.c_str());
  if (j < 0) throw ConfigError(config_.arm_file(), a.joint_name, "joint of actuators.yaml missing in the MJCF");
  if (m_->jnt_type[j] != mjJNT_HINGE && m_->jnt_type[j] != mjJNT_SLIDE) {
    throw ConfigError(config_.arm_file(), a.joint_name, "expected a hinge or slide joint");
  }
  const auto k = static_cast<std::size_t>(i);
  qadr_[k] = m_->jnt_qposadr[j];
  dadr_[k] = m_->jnt_dofadr[j];
  if (m_->jnt_limited[j]) {
    lower_[i] = m_->jnt_range[2 * j];
    upper_[i] = m_->jnt_range[2 * j + 1];
  } else {
    lower_[i] = -100.0;
    upper_[i] = 100.0;
  }
  const double q0 = config_.initial_q_rad[static_cast<std::size_t>(i)];
  if (q0 < lower_[i] || q0 > upper_[i]) {
    throw ConfigError(config_.source, "plant.initial.q_rad[" + std::to_string(i) + "]",
                      std::to_string(q0) + " rad is beyond " + a.joint_name + "'s range [" + std::to_string(lower_[i]) +
                          ", " + std::to_string(upper_[i]) + "] in " + config_.arm_file());
  }
  torque_per_amp_[i] = a.torque_per_amp();
  nominal_torque_per_amp_[i] = config_.actuators[i].torque_per_amp();
  current_limit_[i] = a.current_limit_A;
  max_torque_[i] = a.max_motor_torque_Nm();
  armature_[i] = a.reflected_inertia_kgm2;
  viscous_[i] = a.friction.viscous_Nms_per_rad;
  offsets_[i] = config_.noise.torque_sensor_offset_Nm[k];
  const int d = dadr_[k];
  if (config_.elasticity.enabled) {
    bind_elastic(i);
    return m_->jnt_bodyid[j];
  }
  m_->dof_armature[d] = a.reflected_inertia_kgm2;
  // Dry friction: StickSlipFriction (its spring through qfrc_applied, its damper and the viscous
  // friction through MuJoCo's joint damping, which the Euler step integrates implicitly).
  m_->dof_damping[d] = a.friction.viscous_Nms_per_rad;
  m_->dof_frictionloss[d] = 0.0;
  dry_.emplace_back(dry_friction(config_, a));
  return m_->jnt_bodyid[j];
}

// The rotor inertia and the drive's friction move to the motor side of a spring: the link's MuJoCo
// joint keeps neither armature nor damping.
void SimRobot::bind_elastic(int i) {
  const ActuatorParameters& a = plant_actuators_[i];
  const int d = dadr_[static_cast<std::size_t>(i)];
  m_->dof_armature[d] = 0.0;
  m_->dof_damping[d] = 0.0;
  m_->dof_frictionloss[d] = 0.0;
  ElasticTransmission::Parameters p;
  p.stiffness_Nm_per_rad = config_.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)];
  p.rotor_inertia_kgm2 = a.reflected_inertia_kgm2;
  p.damping_Nms_per_rad = 2.0 * config_.elasticity.damping_ratio * std::sqrt(p.stiffness_Nm_per_rad * p.rotor_inertia_kgm2);
  p.viscous_Nms_per_rad = a.friction.viscous_Nms_per_rad;
  elastic_.emplace_back(p, dry_friction(config_, a));
  dry_.emplace_back();  // unused: keeps the joint indexing of the rigid path
}

// Arm links only; the scene's tool is configured explicitly.
void SimRobot::perturb_link_inertials(const std::vector<int>& arm_bodies) {
  RandomGenerator rng(config_.mismatch.seed, kMismatchStream);
  for (int b : arm_bodies) {
    LinkInertial li;
    li.mass_kg = m_->body_mass[b];
    li.com_m = Eigen::Vector3d(m_->body_ipos[3 * b], m_->body_ipos[3 * b + 1], m_->body_ipos[3 * b + 2]);
    li.principal_kgm2 =
        Eigen::Vector3d(m_->body_inertia[3 * b], m_->body_inertia[3 * b + 1], m_->body_inertia[3 * b + 2]);
    const LinkInertial p = li.perturbed(config_.mismatch.mass_fraction, config_.mismatch.com_fraction,
                                        config_.mismatch.inertia_fraction, rng);
    m_->body_mass[b] = p.mass_kg;
    for (int k = 0; k < 3; ++k) {
      m_->body_ipos[3 * b + k] = p.com_m[k];
      m_->body_inertia[3 * b + k] = p.principal_kgm2[k];
    }
  }
}

void SimRobot::find_ft_sensor() {
  floor_geom_ = mj_name2id(m_.get(), mjOBJ_GEOM, SimScene::kFloorGeom);  // the floor's contacts are truth too
  if (!config_.has_end_of_arm) return;  // a bare flange: no sensor, no tool
  tool_body_ = mj_name2id(m_.get(), mjOBJ_BODY, SimScene::kToolBody);
  if (!config_.has_ft_sensor) {  // a tool on the flange: no sensor to read
    if (tool_body_ < 0) throw ConfigError(config_.source, "scene", "tool body missing from the composed scene");
    return;
  }
  sensor_site_ = mj_name2id(m_.get(), mjOBJ_SITE, SimScene::kSensorSite);
  const int force_sensor = mj_name2id(m_.get(), mjOBJ_SENSOR, SimScene::kForceSensor);
  const int torque_sensor = mj_name2id(m_.get(), mjOBJ_SENSOR, SimScene::kTorqueSensor);
  if (tool_body_ < 0 || sensor_site_ < 0 || force_sensor < 0 || torque_sensor < 0) {
    throw ConfigError(config_.source, "scene", "tool body or F/T sensor missing from the composed scene");
  }
  force_adr_ = m_->sensor_adr[force_sensor];
  torque_adr_ = m_->sensor_adr[torque_sensor];
  // MuJoCo's sensor stage runs its force recursion over every body; the tool's alone gives the same
  // readings at a fraction of the cost. Otherwise (equality constraints, a sensor cutoff) the stage.
  if (SiteWrenchSensor::reproduces(m_.get(), force_sensor, torque_sensor)) {
    ft_readings_ = SiteWrenchSensor(m_.get(), force_sensor, torque_sensor);
    ft_qvel_.assign(static_cast<std::size_t>(m_->nv), 0.0);
  }
}

void SimRobot::find_drop_test() {
  anchor_site_ = mj_name2id(m_.get(), mjOBJ_SITE, SimScene::kAnchorSite);
  drop_body_ = mj_name2id(m_.get(), mjOBJ_BODY, SimScene::kDropBody);
  const int free = m_->body_jntadr[drop_body_];
  drop_qadr_ = m_->jnt_qposadr[free];
  drop_dadr_ = m_->jnt_dofadr[free];
  latch_damping_ = 2.0 * std::sqrt(config_.drop_test.latch_stiffness_N_per_m * config_.drop_test.mass_kg);
}

void SimRobot::find_surrogate() {
  const auto& c = config_.surrogate;
  const auto& r = c.region;
  tool_geom_ = mj_name2id(m_.get(), mjOBJ_GEOM, SimScene::kToolGeom);
  if (tool_geom_ < 0 || m_->geom_type[tool_geom_] != mjGEOM_BOX) throw ConfigError(config_.source, "surrogate", "needs a tool for the body region to meet (no end of arm)");
  if (!(r.mass_kg > 0.0) || !(r.stiffness_N_per_m > 0.0) || !(r.damping_Ns_per_m >= 0.0) || !std::isfinite(r.mass_kg) ||
      !std::isfinite(r.stiffness_N_per_m) || !std::isfinite(r.damping_Ns_per_m)) {
    throw ConfigError(config_.source, "surrogate.region", "needs a finite mass > 0, stiffness > 0 and damping >= 0");
  }
  if (!c.face_m.allFinite() || !c.normal.allFinite() || std::abs(c.normal.norm() - 1.0) > 1e-6 || !(c.face_radius_m > 0.0)) {
    throw ConfigError(config_.source, "surrogate", "needs a finite face position, a unit normal and a face radius > 0");
  }
  surrogate_ = BodyRegionSurrogate(r);
}

void SimRobot::find_disturbance_bodies() {
  for (std::size_t i = 0; i < config_.disturbances.size(); ++i) {
    const auto& f = config_.disturbances[i];
    const int b = mj_name2id(m_.get(), mjOBJ_BODY, f.body.c_str());
    if (b <= 0) {
      throw ConfigError(config_.source, "plant.disturbances[" + std::to_string(i) + "].body",
                        "no body '" + f.body + "' in the scene");
    }
    disturbance_bodies_.push_back(b);
  }
}

// The links random pushes land on (all arm links when the configuration names none).
void SimRobot::find_push_links(const std::vector<int>& arm_bodies) {
  std::vector<std::string> names = config_.random_pushes.links;
  if (names.empty()) {
    for (int b : arm_bodies) names.emplace_back(mj_id2name(m_.get(), mjOBJ_BODY, b));
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    const int b = mj_name2id(m_.get(), mjOBJ_BODY, names[i].c_str());
    const std::string key = "plant.random_pushes.links[" + std::to_string(i) + "]";
    if (b <= 0) throw ConfigError(config_.source, key, "no body '" + names[i] + "' in the scene");
    const int capsule = first_capsule(m_.get(), b);
    if (capsule < 0) throw ConfigError(config_.source, key, "body '" + names[i] + "' has no capsule geom to push on");
    push_links_.push_back(capsule_surface(m_.get(), b, capsule));
  }
}

void SimRobot::make_data() {
  d_.reset(mj_makeData(m_.get()));
  if (!d_) throw ConfigError(config_.source, "scene", "MuJoCo could not allocate its data");
  mj_setConst(m_.get(), d_.get());  // derived constants after the inertial and armature edits
}

// The generic drive's hold gains (GenericDrive::hold_gains' rule where none are given), on each
// joint's inertia at the start posture: MuJoCo's M_ii (armature included) on the link side, plus
// the rotor where an elastic transmission keeps it off the link. Refused where the explicit PD
// step would come near its stability bound at the physics step h: w h or kd h / J_i above 1.
void SimRobot::set_generic_hold_gains() {
  for (int i = 0; i < n_; ++i) d_->qpos[qadr_[static_cast<std::size_t>(i)]] = config_.initial_q_rad[static_cast<std::size_t>(i)];
  mj_forward(m_.get(), d_.get());
  Eigen::VectorXd inertia(n_);
  for (int i = 0; i < n_; ++i) {
    const int dof = dadr_[static_cast<std::size_t>(i)];
    inertia[i] = d_->qM[m_->dof_Madr[dof]] + (config_.elasticity.enabled ? plant_actuators_[i].reflected_inertia_kgm2 : 0.0);
  }
  GenericDrive::hold_gains(inertia, config_.generic_hold, hold_kp_, hold_kd_);
  const double h = config_.physics_step_s();
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const bool kp_rings = hold_kp_[k] * h * h > inertia[i], kd_unstable = hold_kd_[k] * h > inertia[i];
    if (!kp_rings && !kd_unstable) continue;
    // (Appended piece by piece: GCC 12 warns falsely on "literal" + std::to_string.)
    std::string key = kp_rings ? "drive.position_hold.kp_Nm_per_rad[" : "drive.position_hold.kd_Nms_per_rad[";
    key += std::to_string(i);
    key += ']';
    std::string reason = format_general(kp_rings ? hold_kp_[k] : hold_kd_[k], 6);
    reason += kp_rings ? " N.m/rad on " : " N.m.s/rad on ";
    reason += plant_actuators_[i].joint_name;
    reason += " (inertia ";
    reason += format_general(inertia[i], 4);
    reason += kp_rings ? " kg.m^2 at the start posture): the hold would ring at the plant's step (kp h^2 / J > 1)"
                       : " kg.m^2 at the start posture): the hold would be unstable at the plant's step (kd h / J > 1)";
    throw ConfigError(config_.source, key, reason);
  }
}

void SimRobot::allocate_buffers() {
  command_ = RobotCommand(n_);
  pending_ = RobotCommand(n_);
  state_ = RobotState(n_);
  // Per-step buffers and truth, sized once here: read() and write() do not allocate.
  for (Eigen::VectorXd* v : {&q_meas_, &qd_meas_, &tau_meas_, &current_, &tau_motor_, &tau_viscous_, &tau_dry_, &tau_s_,
                             &hold_damping_, &deflection_torque_, &v_before_, &f_dry_, &damping_, &qdd_, &truth_.q_rad,
                             &truth_.qd_rad_s, &truth_.qdd_rad_s2, &truth_.current_A, &truth_.tau_motor_Nm, &truth_.tau_friction_Nm,
                             &truth_.tau_transmitted_Nm, &truth_.q_motor_rad, &q_before_}) {
    *v = Eigen::VectorXd::Zero(n_);
  }
  noise_draws_.assign(static_cast<std::size_t>(std::max(3 * n_, 6)), 0.0);
}

void SimRobot::reset() {
  mj_resetData(m_.get(), d_.get());
  restart_noise_and_counters();
  const Eigen::Vector3d drop_force_on_tool = place_initial_pose();
  mj_forward(m_.get(), d_.get());  // kinematics, bias forces, Jacobians at the initial pose
  const Eigen::VectorXd hold = holding_torque(drop_force_on_tool);
  start_drives_holding(hold);
  take_initial_ft_sample(hold);
  sample_state();
  state_.cycle = 0;
}

void SimRobot::set_surrogate_face(const Eigen::Vector3d& face, const Eigen::Vector3d& normal) {
  config_.surrogate.face_m = face;
  config_.surrogate.normal = normal.normalized();
  surrogate_.reset();
}

int SimRobot::body_id(const std::string& name) const {
  const int b = mj_name2id(m_.get(), mjOBJ_BODY, name.c_str());
  return b > 0 ? b : -1;
}

void SimRobot::set_live_disturbance(int body, const ExternalForce& force) {
  live_body_ = body > 0 && body < m_->nbody ? body : -1;
  // Field by field: the body name is not copied (no allocation).
  live_force_.point_m = force.point_m;
  live_force_.frame = force.frame;
  live_force_.force_N = force.force_N;
  live_force_.torque_Nm = force.torque_Nm;
  live_force_.profile = force.profile;
  live_force_.start_s = force.start_s;
  live_force_.duration_s = force.duration_s;
  live_force_.rise_s = force.rise_s;
}

void SimRobot::push(int target, const Eigen::Vector3d& point_m, const Eigen::Vector3d& force_world_N, double hold_s) {
  ExternalForce force;  // no body name: no allocation
  force.point_m = point_m;
  force.frame = ExternalForce::Frame::kWorld;
  force.force_N = force_world_N;
  force.profile = ExternalForce::Profile::kStep;
  force.start_s = state_.time_s;
  force.duration_s = hold_s;
  set_live_disturbance(target, force);
}

void SimRobot::restart_noise_and_counters() {
  joint_noise_.reseed(config_.seed, kJointNoiseStream);
  ft_noise_.reseed(config_.seed, kFtNoiseStream);
  pushes_ = RandomPushGenerator(config_.random_pushes, push_links_, config_.seed);
  fault_ = false;
  has_pending_ = false;
  live_body_ = -1;
  filter_phase_ = 0;
  ft_phase_ = 0;
  wrench_sequence_ = 0;
  state_ = RobotState(n_);
  truth_.drop_released = false;
  truth_.cable_force_N = 0.0;
  surrogate_.reset();
  surrogate_peak_ = 0.0;
}

Eigen::Vector3d SimRobot::place_initial_pose() {
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    d_->qpos[qadr_[k]] = config_.initial_q_rad[k];
    dry_[k].reset(config_.initial_q_rad[k]);
  }
  mj_kinematics(m_.get(), d_.get());
  if (drop_body_ < 0) return Eigen::Vector3d::Zero();
  // Where this run's hand holds the mass relative to the anchor (world axes, z up).
  RandomGenerator release(config_.seed, kReleaseStream);
  const double h = config_.drop_test.release_horizontal_spread_m;
  const double v = config_.drop_test.release_vertical_spread_m;
  release_offset_ = Eigen::Vector3d(release.uniform(-h, h), release.uniform(-h, h), release.uniform(-v, v));
  // The mass hangs on the latch at its static deflection m g / k below the held point.
  const double k = config_.drop_test.latch_stiffness_N_per_m;
  const Eigen::Vector3d g(m_->opt.gravity[0], m_->opt.gravity[1], m_->opt.gravity[2]);
  const mjtNum* anchor = d_->site_xpos + 3 * anchor_site_;
  const Eigen::Vector3d p =
      Eigen::Vector3d(anchor[0], anchor[1], anchor[2]) + release_offset_ + config_.drop_test.mass_kg * g / k;
  for (int k3 = 0; k3 < 3; ++k3) d_->qpos[drop_qadr_ + k3] = p[k3];
  d_->qpos[drop_qadr_ + 3] = 1.0;
  d_->qpos[drop_qadr_ + 4] = d_->qpos[drop_qadr_ + 5] = d_->qpos[drop_qadr_ + 6] = 0.0;
  hand_point_ = Eigen::Vector3d(anchor[0], anchor[1], anchor[2]) + release_offset_;
  // A hand carries the weight itself: the arm holds only its own (and the slack cable's nothing).
  if (config_.drop_test.held_by_hand) return Eigen::Vector3d::Zero();
  return config_.drop_test.mass_kg * g;
}

// The arm starts at rest, already holding itself (and the latched drop mass): the holding torque
// is the bias force minus the generalized force of the mass's weight at the anchor.
Eigen::VectorXd SimRobot::holding_torque(const Eigen::Vector3d& drop_force_on_tool) const {
  Eigen::VectorXd hold = Eigen::VectorXd::Zero(n_);
  for (int i = 0; i < n_; ++i) hold[i] = d_->qfrc_bias[dadr_[static_cast<std::size_t>(i)]];
  if (drop_body_ < 0) return hold;
  std::vector<mjtNum> jacp(static_cast<std::size_t>(3 * m_->nv));
  mj_jacSite(m_.get(), d_.get(), jacp.data(), nullptr, anchor_site_);
  for (int i = 0; i < n_; ++i) {
    const int d = dadr_[static_cast<std::size_t>(i)];
    double gen = 0.0;
    for (int r = 0; r < 3; ++r) gen += jacp[static_cast<std::size_t>(r * m_->nv + d)] * drop_force_on_tool[r];
    hold[i] -= gen;
  }
  return hold;
}

// The drives' state holding `hold`, and the initial command: hold the initial pose in Position mode.
void SimRobot::start_drives_holding(const Eigen::VectorXd& hold) {
  for (int i = 0; i < n_; ++i) {
    tau_motor_[i] = hold[i];
    current_[i] = hold[i] / torque_per_amp_[i];
    tau_s_[i] = hold[i];
  }
  tau_viscous_.setZero();
  tau_dry_.setZero();
  f_dry_.setZero();
  qdd_.setZero();

  for (std::size_t k = 0; k < elastic_.size(); ++k) elastic_[k].reset(config_.initial_q_rad[k], hold[static_cast<int>(k)]);
  tau_meas_ = tau_s_ + offsets_;
  deflection_torque_ = tau_meas_;
  // The servo holds what its encoder reads now (a motor-side encoder reads the wound spring too).
  command_.mode = LowLevelMode::kPosition;
  for (int i = 0; i < n_; ++i) {
    command_.q_rad[i] = elastic() ? servo_position(i) : config_.initial_q_rad[static_cast<std::size_t>(i)];
    q_meas_[i] = quantize(servo_position(i));
  }
  drive_ = make_drive_loops(config_, hold_kp_, hold_kd_);
  drive_->allow_implicit_damping(!elastic());
  drive_->begin_cycle(command_, false, q_meas_, vendor_torque());
  drive_->start_holding(vendor_torque());
}

// Initial F/T sample with the arm held (qacc ~ 0) and the latch carrying the mass.
void SimRobot::take_initial_ft_sample(const Eigen::VectorXd& hold) {
  if (sensor_site_ < 0) return;
  for (int i = 0; i < n_; ++i) d_->qfrc_applied[dadr_[static_cast<std::size_t>(i)]] = hold[i];
  mju_zero(d_->xfrc_applied, 6 * m_->nbody);
  apply_drop_forces(0.0);
  m_->opt.disableflags &= ~mjDSBL_SENSOR;
  mj_forward(m_.get(), d_.get());
  m_->opt.disableflags |= mjDSBL_SENSOR;
  sample_ft_sensor(d_->sensordata + force_adr_, d_->sensordata + torque_adr_);
  wrench_sequence_ = 1;
  wrench_stamp_ = 0.0;
  truth_.wrench_sensor = wrench_true_;
}

// The wrench from MuJoCo's sensor readings, and its measurement.
void SimRobot::sample_ft_sensor(const double* force, const double* torque) {
  for (int k = 0; k < 3; ++k) {
    wrench_true_[k] = kWrenchSign * force[k];
    wrench_true_[3 + k] = kWrenchSign * torque[k];
  }
  const auto& ft = config_.ft_sensor;
  // The draws in the order of one normal(std) per axis, force then torque (none for a zero std).
  const bool noisy_force = ft.force_std_N != 0.0, noisy_torque = ft.torque_std_Nm != 0.0;
  const double* draw = noise_draws_.data();
  ft_noise_.fill_normal(noise_draws_.data(), 3 * (int{noisy_force} + int{noisy_torque}));
  for (int k = 0; k < 3; ++k) {
    wrench_meas_[k] = wrench_true_[k] + ft.force_bias_N[k] + (noisy_force ? ft.force_std_N * *draw++ : 0.0);
    wrench_meas_[3 + k] = wrench_true_[3 + k] + ft.torque_bias_Nm[k] + (noisy_torque ? ft.torque_std_Nm * *draw++ : 0.0);
  }
}

// std::round(x) (half away from zero) without its libm call: x - trunc(x) is exact, so stepping
// away from zero where that fraction reaches one half gives std::round's result to the bit.
double SimRobot::quantize(double q) const {
  if (quantum_ <= 0.0) return q;
  const double x = q / quantum_;
  const double whole = std::trunc(x);
  return quantum_ * (std::abs(x - whole) >= 0.5 ? whole + std::copysign(1.0, x) : whole);
}

namespace {
constexpr double kMaxFollowingError_rad = 5.0 * 3.14159265358979323846 / 180.0;
}  // namespace

WriteStatus SimRobot::validate(const RobotCommand& c) const {
  if (fault_) return WriteStatus::kFault;
  if (!is_valid(c.mode)) return WriteStatus::kInvalidMode;
  if (!drive_->offered().contains(c.mode)) return WriteStatus::kInvalidMode;  // a loop these drives lack
  const Eigen::VectorXd* v = nullptr;
  switch (c.mode) {
    case LowLevelMode::kPosition: v = &c.q_rad; break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
    case LowLevelMode::kTorque: v = &c.tau_Nm; break;
    case LowLevelMode::kCurrent: v = &c.current_A; break;
  }
  if (v->size() != n_) return WriteStatus::kSizeMismatch;
  if (!v->allFinite()) return WriteStatus::kNotFinite;
  for (int i = 0; i < n_; ++i) {
    const double x = (*v)[i];
    switch (c.mode) {
      case LowLevelMode::kPosition:
        if (x < lower_[i] || x > upper_[i]) return WriteStatus::kOutOfRange;
        // A set-point further from the joint than Kinova's following-error fault (5 degrees,
        // Kortex low-level servoing) is refused, as the robot would fault on it: no step of any
        // size reaches the servo.
        if (std::abs(x - d_->qpos[qadr_[static_cast<std::size_t>(i)]]) > kMaxFollowingError_rad) {
          return WriteStatus::kOutOfRange;
        }
        break;
      case LowLevelMode::kKinovaTorque:
      case LowLevelMode::kKinovaTorqueHighVelocity:
      case LowLevelMode::kTorque:
        if (std::abs(x) > max_torque_[i]) return WriteStatus::kOutOfRange;
        break;
      case LowLevelMode::kCurrent:
        if (std::abs(x) > current_limit_[i]) return WriteStatus::kOutOfRange;
        break;
    }
  }
  return WriteStatus::kOk;
}

WriteStatus SimRobot::write(const RobotCommand& command) {
  const WriteStatus status = validate(command);
  state_.last_write_status = status;
  if (status != WriteStatus::kOk) {
    ++state_.rejected_writes;
    return status;
  }
  pending_.copy_setpoint(command);
  has_pending_ = true;
  return WriteStatus::kOk;
}

const RobotState& SimRobot::read() {
  if (fault_) {
    ++state_.cycle;
    return state_;
  }
  const bool fresh = has_pending_;
  if (fresh) {
    command_.copy_setpoint(pending_);
    has_pending_ = false;
  }
  drive_->begin_cycle(command_, fresh, q_meas_, vendor_torque());
  // The mode is set for the period: what its loop reads, asked once.
  drive_reads_position_ = drive_->uses_position();
  drive_reads_velocity_ = drive_->uses_velocity();
  drive_reads_torque_ = drive_->uses_torque();
  surrogate_peak_ = 0.0;
  for (int s = 0; s < substeps_; ++s) substep(s == substeps_ - 1);
  if (d_->warning[mjWARN_BADQACC].number > 0 || d_->warning[mjWARN_BADQVEL].number > 0 ||
      d_->warning[mjWARN_BADQPOS].number > 0) {
    fault_ = true;
  }
  sample_state();
  return state_;
}

Eigen::VectorXd SimRobot::joint_inertia_diagonal() const {
  Eigen::VectorXd m(n_);
  for (int i = 0; i < n_; ++i) m[i] = d_->qM[m_->dof_Madr[dadr_[static_cast<std::size_t>(i)]]];
  return m;
}

// With the deflection compensated, the drive's own torque reading, low-passed, over its stiffness.
double SimRobot::servo_position(int i) const {
  const auto k = static_cast<std::size_t>(i);
  if (!motor_encoder_) return d_->qpos[qadr_[k]];
  const double rotor = elastic_[k].position();
  return compensate_deflection_ ? rotor - deflection_torque_[i] / config_.elasticity.stiffness_Nm_per_rad[k] : rotor;
}

double SimRobot::servo_velocity(int i) const {
  return motor_encoder_ ? elastic_[static_cast<std::size_t>(i)].velocity() : d_->qvel[dadr_[static_cast<std::size_t>(i)]];
}

// Rigid: dry friction from the current state (its damping enters MuJoCo's passive forces in
// mj_step1 and the implicit part of the Euler step); the link carries motor torque and friction.
void SimRobot::prepare_rigid() {
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int d = dadr_[k];
    v_before_[i] = d_->qvel[d];
    f_dry_[i] = dry_[k].update(d_->qpos[qadr_[k]], d_->qvel[d]);
    damping_[i] = viscous_[i] + dry_[k].damping();
    m_->dof_damping[d] = damping_[i];
  }
}

// Elastic: the link carries the spring's torque from the state at the step's start (f_dry_ holds it).
void SimRobot::prepare_elastic() {
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int d = dadr_[k];
    v_before_[i] = d_->qvel[d];
    q_before_[i] = d_->qpos[qadr_[k]];
    f_dry_[i] = elastic_[k].spring_torque(q_before_[i], v_before_[i]);
  }
}

// Transmitted torque: motor torque, minus friction and rotor inertia on the motor side. The
// damping (viscous + presliding) acted on the new velocity, and the step's acceleration is
// (v1 - v0) / dt (d->qacc is MuJoCo's explicit value, before the implicit damping).
void SimRobot::finish_rigid() {
  for (int i = 0; i < n_; ++i) {
    const int d = dadr_[static_cast<std::size_t>(i)];
    const double v1 = d_->qvel[d];
    qdd_[i] = (v1 - v_before_[i]) / m_->opt.timestep;
    tau_viscous_[i] = -viscous_[i] * v1;
    tau_dry_[i] = f_dry_[i] - (damping_[i] - viscous_[i]) * v1;
    if (hold_damping_[i] != 0.0) {  // the motor carried the drive's damping too
      tau_motor_[i] -= hold_damping_[i] * v1;
      current_[i] = tau_motor_[i] / torque_per_amp_[i];
    }
    tau_s_[i] = tau_motor_[i] + tau_viscous_[i] + tau_dry_[i] - armature_[i] * qdd_[i];
  }
}

// The rotors advance over the same step (link state at its start); the sensor reads the spring.
void SimRobot::finish_elastic() {
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int d = dadr_[k];
    const double v1 = d_->qvel[d];
    qdd_[i] = (v1 - v_before_[i]) / m_->opt.timestep;
    elastic_[k].step(tau_motor_[i], q_before_[i], v_before_[i], m_->opt.timestep);
    tau_viscous_[i] = -viscous_[i] * elastic_[k].velocity();
    tau_dry_[i] = elastic_[k].friction_torque() - tau_viscous_[i];
    tau_s_[i] = elastic_[k].spring_torque(d_->qpos[qadr_[k]], v1);
  }
}

void SimRobot::substep(bool last_of_period) {
  // 1. Friction or spring from the current state, then positions, velocities, bias forces.
  if (elastic()) {
    prepare_elastic();
  } else {
    prepare_rigid();
  }
  mj_step1(m_.get(), d_.get());
  const double t = d_->time;

  // 2. The drives' sensors and the vendor loop. The encoder is read when the loop closes on
  //    position, and at the period's last step for the next period's mode entry (begin_cycle).
  const bool read_encoder = drive_reads_position_ || last_of_period;
  const double sv = config_.noise.velocity_std_rad_s;
  const double st = config_.noise.torque_sensor_std_Nm;
  // A servo that compensates the deflection reads the torque sensor with its encoder.
  const bool read_torque = drive_reads_torque_ || (compensate_deflection_ && drive_reads_position_);
  // The draws in the order of one normal(std) per reading, joint by joint (none for a zero std).
  const bool noisy_velocity = drive_reads_velocity_ && sv != 0.0, noisy_torque = read_torque && st != 0.0;
  const double* draw = noise_draws_.data();
  joint_noise_.fill_normal(noise_draws_.data(), n_ * (int{noisy_velocity} + int{noisy_torque}));
  for (int i = 0; i < n_; ++i) {
    qd_meas_[i] = servo_velocity(i) + (noisy_velocity ? sv * *draw++ : 0.0);
    tau_meas_[i] = tau_s_[i] + offsets_[i] + (noisy_torque ? st * *draw++ : 0.0);
    if (compensate_deflection_) deflection_torque_[i] += deflection_alpha_ * (tau_meas_[i] - deflection_torque_[i]);
    if (read_encoder) q_meas_[i] = quantize(servo_position(i));
  }
  drive_->tick(q_meas_, qd_meas_, tau_meas_, filter_phase_ == 0, current_);

  // 3. Joint torques: rigid, motor and the explicit part of the dry friction; elastic, the spring.
  //    A rigid joint's drive damping c (DriveLoops::implicit_damping) acts as -c v1 like the viscous
  //    friction: -c v0 here, the rest through dof_damping in the step's implicit part.
  for (int i = 0; i < n_; ++i) {
    const int d = dadr_[static_cast<std::size_t>(i)];
    tau_motor_[i] = torque_per_amp_[i] * current_[i];
    if (elastic()) {
      d_->qfrc_applied[d] = f_dry_[i];
      continue;
    }
    hold_damping_[i] = drive_->implicit_damping(i);
    d_->qfrc_applied[d] = tau_motor_[i] + f_dry_[i] - hold_damping_[i] * v_before_[i];
    m_->dof_damping[d] = damping_[i] + hold_damping_[i];
  }

  // 4. External forces.
  mju_zero(d_->xfrc_applied, 6 * m_->nbody);
  apply_external_forces(t);

  // 5. Step, with the F/T sensor evaluated on its sampling steps only (by MuJoCo's sensor stage
  //    when ft_readings_ cannot stand in for it).
  const bool ft_step = sensor_site_ >= 0 && ft_phase_ == ft_decimation_ - 1;
  const bool ft_by_mujoco = ft_step && !ft_readings_.bound();
  if (ft_step && !ft_by_mujoco) mju_copy(ft_qvel_.data(), d_->qvel, m_->nv);
  if (ft_by_mujoco) m_->opt.disableflags &= ~mjDSBL_SENSOR;
  mj_step2(m_.get(), d_.get());
  if (ft_by_mujoco) m_->opt.disableflags |= mjDSBL_SENSOR;

  if (elastic()) {
    finish_elastic();
  } else {
    finish_rigid();
  }

  // 6. F/T sample.
  if (ft_step) {
    if (ft_by_mujoco) {
      sample_ft_sensor(d_->sensordata + force_adr_, d_->sensordata + torque_adr_);
    } else {
      double force[3], torque[3];
      ft_readings_.evaluate(m_.get(), d_.get(), ft_qvel_.data(), force, torque);
      sample_ft_sensor(force, torque);
    }
    ++wrench_sequence_;
    wrench_stamp_ = t;
  }
  // Steps since the reset, modulo the slower loops' decimations.
  if (++filter_phase_ == filter_decimation_) filter_phase_ = 0;
  if (++ft_phase_ == ft_decimation_) ft_phase_ = 0;
}

void SimRobot::apply_force(int body, const Eigen::Vector3d& point_local, bool local_frame, const Eigen::Vector3d& force,
                           const Eigen::Vector3d& torque) {
  const Eigen::Matrix3d R = rotation(d_->xmat + 9 * body);
  const Eigen::Vector3d x(d_->xpos[3 * body], d_->xpos[3 * body + 1], d_->xpos[3 * body + 2]);
  const Eigen::Vector3d com(d_->xipos[3 * body], d_->xipos[3 * body + 1], d_->xipos[3 * body + 2]);
  const Eigen::Vector3d p = x + R * point_local;
  const Eigen::Vector3d f = local_frame ? Eigen::Vector3d(R * force) : force;
  const Eigen::Vector3d m = (local_frame ? Eigen::Vector3d(R * torque) : torque) + (p - com).cross(f);
  mjtNum* out = d_->xfrc_applied + 6 * body;
  for (int k = 0; k < 3; ++k) {
    out[k] += f[k];
    out[3 + k] += m[k];
  }
}

void SimRobot::apply_external_forces(double t) {
  if (tool_geom_ >= 0) apply_surrogate_force();
  for (std::size_t i = 0; i < config_.disturbances.size(); ++i) {
    const ExternalForce& f = config_.disturbances[i];
    const double s = f.scale_at(t);
    if (s == 0.0) continue;
    apply_force(disturbance_bodies_[i], f.point_m, f.frame == ExternalForce::Frame::kLocal, s * f.force_N,
                s * f.torque_Nm);
  }
  if (live_body_ > 0) {
    const double s = live_force_.scale_at(t);
    if (s != 0.0) {
      apply_force(live_body_, live_force_.point_m, live_force_.frame == ExternalForce::Frame::kLocal,
                  s * live_force_.force_N, s * live_force_.torque_Nm);
    }
  }
  if (const RandomPushGenerator::Push* push = pushes_.active(t)) {
    const double s = push->scale_at(t);
    if (s > 0.0) {
      apply_force(push->body, push->point_local, true, s * push->peak_force_N * push->direction_local,
                  Eigen::Vector3d::Zero());
    }
  }
  apply_drop_forces(t);
}

void SimRobot::apply_drop_forces(double t) {
  if (drop_body_ < 0) return;
  const auto& cfg = config_.drop_test;
  if (!truth_.drop_released && t >= cfg.release_time_s) truth_.drop_released = true;

  const mjtNum* a = d_->site_xpos + 3 * anchor_site_;
  const Eigen::Vector3d anchor(a[0], a[1], a[2]);
  mjtNum v6[6];
  mj_objectVelocity(m_.get(), d_.get(), mjOBJ_SITE, anchor_site_, v6, 0);  // (angular; linear), world axes
  const Eigen::Vector3d anchor_velocity(v6[3], v6[4], v6[5]);
  const Eigen::Vector3d p(d_->qpos[drop_qadr_], d_->qpos[drop_qadr_ + 1], d_->qpos[drop_qadr_ + 2]);
  const Eigen::Vector3d v(d_->qvel[drop_dadr_], d_->qvel[drop_dadr_ + 1], d_->qvel[drop_dadr_ + 2]);
  const Eigen::Vector3d rel = p - anchor;
  const Eigen::Vector3d rel_v = v - anchor_velocity;

  Eigen::Vector3d on_mass = Eigen::Vector3d::Zero();
  Eigen::Vector3d on_mass_by_hand = Eigen::Vector3d::Zero();  // from the world: no reaction on the arm
  if (!truth_.drop_released && cfg.held_by_hand) {
    on_mass_by_hand = -cfg.latch_stiffness_N_per_m * (p - hand_point_) - latch_damping_ * v;
  } else if (!truth_.drop_released) {
    on_mass = -cfg.latch_stiffness_N_per_m * (rel - release_offset_) - latch_damping_ * rel_v;
  }
  const double length = rel.norm();
  double tension = 0.0;
  if (length > cfg.cable_length_m) {
    const Eigen::Vector3d u = rel / length;
    tension = std::max(0.0, cfg.cable_stiffness_N_per_m * (length - cfg.cable_length_m) +
                                cfg.cable_damping_Ns_per_m * u.dot(rel_v));
    on_mass -= tension * u;
  }
  truth_.cable_length_m = length;
  truth_.cable_force_N = tension;
  mjtNum* fm = d_->xfrc_applied + 6 * drop_body_;
  for (int k = 0; k < 3; ++k) fm[k] += on_mass_by_hand[k];
  if (on_mass.squaredNorm() == 0.0) return;
  // On the mass at its centre; the reaction on the tool at the anchor (world axes).
  for (int k = 0; k < 3; ++k) fm[k] += on_mass[k];
  const Eigen::Vector3d com(d_->xipos[3 * tool_body_], d_->xipos[3 * tool_body_ + 1], d_->xipos[3 * tool_body_ + 2]);
  const Eigen::Vector3d m = (anchor - com).cross(-on_mass);
  mjtNum* ft = d_->xfrc_applied + 6 * tool_body_;
  for (int k = 0; k < 3; ++k) {
    ft[k] -= on_mass[k];
    ft[3 + k] += m[k];
  }
}

const Eigen::VectorXd& SimRobot::vendor_torque() {
  vendor_torque_ = nominal_torque_per_amp_.cwiseProduct(current_);
  return vendor_torque_;
}

void SimRobot::sample_state() {
  const double t = d_->time;
  const auto& z = config_.noise;
  bool joints_ok = true;
  bool torque_ok = true;
  bool current_ok = true;
  // The draws in the order of one normal(std) per reading, joint by joint (none for a zero std).
  const bool noisy_velocity = z.velocity_std_rad_s != 0.0, noisy_torque = z.torque_sensor_std_Nm != 0.0,
             noisy_current = z.current_std_A != 0.0;
  const double* draw = noise_draws_.data();
  joint_noise_.fill_normal(noise_draws_.data(), n_ * (int{noisy_velocity} + int{noisy_torque} + int{noisy_current}));
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double q = d_->qpos[qadr_[k]];
    const double qd = d_->qvel[dadr_[k]];
    state_.q_rad[i] = quantize(q);
    state_.qd_rad_s[i] = qd + (noisy_velocity ? z.velocity_std_rad_s * *draw++ : 0.0);
    state_.tau_sensor_Nm[i] = tau_s_[i] + offsets_[i] + (noisy_torque ? z.torque_sensor_std_Nm * *draw++ : 0.0);
    state_.current_A[i] = current_[i] + (noisy_current ? z.current_std_A * *draw++ : 0.0);
    joints_ok = joints_ok && std::isfinite(state_.q_rad[i]) && std::isfinite(state_.qd_rad_s[i]);
    torque_ok = torque_ok && std::isfinite(state_.tau_sensor_Nm[i]);
    current_ok = current_ok && std::isfinite(state_.current_A[i]);
    truth_.q_rad[i] = q;
    truth_.q_motor_rad[i] = elastic() ? elastic_[k].position() : q;
    truth_.qd_rad_s[i] = qd;
    truth_.qdd_rad_s2[i] = qdd_[i];
    truth_.current_A[i] = current_[i];
    truth_.tau_motor_Nm[i] = tau_motor_[i];
    truth_.tau_friction_Nm[i] = tau_viscous_[i] + tau_dry_[i];
    truth_.tau_transmitted_Nm[i] = tau_s_[i];
  }
  if (!joints_ok || !torque_ok || !current_ok || !wrench_meas_.allFinite()) fault_ = true;
  state_.time_s = t;
  ++state_.cycle;
  state_.mode = drive_->mode();
  state_.fault = fault_;
  for (SignalStatus* s : {&state_.joints, &state_.torque, &state_.current}) {
    ++s->sequence;
    s->stamp_s = t;
  }
  state_.joints.valid = joints_ok && !fault_;
  state_.torque.valid = torque_ok && !fault_;
  state_.current.valid = current_ok && !fault_;
  if (wrench_sequence_ != state_.wrench.sequence) {
    state_.wrench_sensor = wrench_meas_;
    state_.wrench.sequence = wrench_sequence_;
    state_.wrench.stamp_s = wrench_stamp_;
  }
  // No F/T sensor: no sample ever, and the wrench is never valid.
  state_.wrench.valid = sensor_site_ >= 0 && wrench_meas_.allFinite() && !fault_;

  truth_.time_s = t;
  truth_.wrench_sensor = wrench_true_;
  if (sensor_site_ >= 0) {
    const mjtNum* sp = d_->site_xpos + 3 * sensor_site_;
    truth_.sensor_position_m = Eigen::Vector3d(sp[0], sp[1], sp[2]);
    truth_.sensor_rotation = rotation(d_->site_xmat + 9 * sensor_site_);
  }
  if (drop_body_ >= 0) {
    truth_.drop_mass_position_m = Eigen::Vector3d(d_->qpos[drop_qadr_], d_->qpos[drop_qadr_ + 1], d_->qpos[drop_qadr_ + 2]);
    truth_.drop_mass_velocity_m_s = Eigen::Vector3d(d_->qvel[drop_dadr_], d_->qvel[drop_dadr_ + 1], d_->qvel[drop_dadr_ + 2]);
  }
  truth_.last_push = pushes_.latest();
  truth_.floor_normal_force_N = floor_geom_ >= 0 ? floor_normal_force() : 0.0;
  truth_.surrogate_force_N = surrogate_.force_N();
  truth_.surrogate_peak_force_N = surrogate_peak_;
  truth_.surrogate_compression_m = surrogate_.compression_m();
  truth_.surrogate_displacement_m = surrogate_.displacement_m();
}

namespace {
// How far a box (centre c, axes, half sizes h) reaches from its centre along the unit `direction`
// (its support function): sum_i h_i |a_i . direction|.
double box_reach(const Eigen::Matrix3d& axes, const mjtNum* half, const Eigen::Vector3d& direction) {
  double reach = 0.0;
  for (int i = 0; i < 3; ++i) reach += half[i] * std::abs(direction.dot(axes.col(i)));
  return reach;
}
}  // namespace

Eigen::Vector3d SimRobot::tool_point_along(const Eigen::Vector3d& direction) const {
  if (tool_geom_ < 0) return Eigen::Vector3d::Zero();  // no surrogate bound: no tool box
  const Eigen::Matrix3d axes = rotation(d_->geom_xmat + 9 * tool_geom_);
  const Eigen::Vector3d centre(d_->geom_xpos[3 * tool_geom_], d_->geom_xpos[3 * tool_geom_ + 1], d_->geom_xpos[3 * tool_geom_ + 2]);
  return centre + box_reach(axes, m_->geom_size + 3 * tool_geom_, direction) * direction;
}

Eigen::Vector3d SimRobot::tool_velocity() const {
  if (tool_geom_ < 0) return Eigen::Vector3d::Zero();
  mjtNum v[6];
  mj_objectVelocity(m_.get(), d_.get(), mjOBJ_GEOM, tool_geom_, v, 0);
  return {v[3], v[4], v[5]};
}

// The body region's force on the tool (body_region_surrogate.hpp). The depth is exact (the box's
// reach along the face's inward normal); the box is over the face when its centre is; the force
// acts at the deepest corner, moved toward the middle of the box's face as that face turns square
// to the normal (within ~6 degrees: kSquare), so that a face meeting the face flat pushes at its
// middle and a slight tilt does not throw the point from one corner to the other.
void SimRobot::apply_surrogate_force() {
  constexpr double kSquare = 0.1;
  const auto& c = config_.surrogate;
  const Eigen::Matrix3d axes = rotation(d_->geom_xmat + 9 * tool_geom_);
  const mjtNum* half = m_->geom_size + 3 * tool_geom_;
  const Eigen::Vector3d centre(d_->geom_xpos[3 * tool_geom_], d_->geom_xpos[3 * tool_geom_ + 1], d_->geom_xpos[3 * tool_geom_ + 2]);
  const Eigen::Vector3d from_face = centre - c.face_m;
  const double height = from_face.dot(c.normal);
  const double depth = box_reach(axes, half, c.normal) - height;
  const bool over_face = (from_face - height * c.normal).norm() <= c.face_radius_m;
  const double force = surrogate_.step(depth, over_face, m_->opt.timestep);
  surrogate_peak_ = std::max(surrogate_peak_, force);
  if (force == 0.0) return;
  Eigen::Vector3d point = centre;
  for (int i = 0; i < 3; ++i) {
    const double along = -c.normal.dot(axes.col(i));
    point += half[i] * std::clamp(along / kSquare, -1.0, 1.0) * axes.col(i);
  }
  const int body = m_->geom_bodyid[tool_geom_];
  const Eigen::Matrix3d R = rotation(d_->xmat + 9 * body);
  const Eigen::Vector3d origin(d_->xpos[3 * body], d_->xpos[3 * body + 1], d_->xpos[3 * body + 2]);
  apply_force(body, R.transpose() * (point - origin), false, force * c.normal, Eigen::Vector3d::Zero());
}

// The normal force of every contact between the floor and a geom of the arm or its tool.
double SimRobot::floor_normal_force() const {
  double total = 0.0;
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    if (c.geom1 != floor_geom_ && c.geom2 != floor_geom_) continue;
    const int other = c.geom1 == floor_geom_ ? c.geom2 : c.geom1;
    if (drop_body_ >= 0 && m_->geom_bodyid[other] == drop_body_) continue;
    mjtNum force[6];
    mj_contactForce(m_.get(), d_.get(), i, force);
    total += force[0];
  }
  return total;
}

const StickSlipFriction::Parameters& SimRobot::dry_friction_parameters(int i) const {
  const auto k = static_cast<std::size_t>(i);
  return elastic() ? elastic_[k].dry_friction().parameters() : dry_[k].parameters();
}

}  // namespace phri
