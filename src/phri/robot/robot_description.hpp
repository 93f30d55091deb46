#pragma once
// phri::RobotDescription: what a robot is, whoever drives it (the MuJoCo plant, the Kortex
// backend, the emulators): its URDF and locked joints, its actuators (actuators.yaml), where it
// stands (base link, gravity, base placement), its home posture, its end of arm (F/T sensor
// placement and tool), payloads on its links, and whose drives it has. A robot bundle
// (config/robot_bundle.hpp) or a plant YAML (config/sim_robot_config.hpp) fills it; the
// simulator's configuration is this plus plant-only settings; every backend takes it.
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/drive_kind.hpp>
#include <phri/robot/end_of_arm.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace phri {

class YamlReader;

/// A generic drive's position hold (sim/generic_drive.hpp), per joint; a list left empty takes the default
/// rule of GenericDrive::hold_gains (critically damped at 30 Hz on the joint's inertia).
struct GenericHoldGains {
  std::vector<double> kp_Nm_per_rad;
  std::vector<double> kd_Nms_per_rad;
};

/// The `drive:` key of robot.yaml and of a plant YAML, one grammar for both:
///   drive: kinova | generic
///   drive: {kind: generic, position_hold: {kp_Nm_per_rad: [...], kd_Nms_per_rad: [...]}}
/// `drive` is the key's node; `dof` the joints. Gains of a `kinova` drive are refused (its
/// position servo is the plant's vendor.position). Throws ConfigError naming the key path.
DriveKind parse_drive(const YamlReader& drive, int dof, GenericHoldGains& hold);

/// Bounds of a generic drive's hold gains. Kp: at least 1 N.m/rad (below, 1 N.m moves the joint a whole
/// radian: no hold), at most 1e6 N.m/rad (the torsional stiffness of the largest robot gearboxes; a
/// servo cannot be stiffer than the gearbox it acts through). Kd: at most 1e4 N.m.s/rad (1e3 x the
/// viscous friction of a large joint).
inline constexpr double kMinHoldKp_Nm_per_rad = 1.0;
inline constexpr double kMaxHoldKp_Nm_per_rad = 1.0e6;
inline constexpr double kMaxHoldKd_Nms_per_rad = 1.0e4;

struct RobotDescription {
  int dof() const { return actuators.size(); }

  /// The arm's URDF (the controller's model; the simulator generates its plant from it unless it has an MJCF).
  std::string urdf_path;
  std::vector<std::string> locked_joints;  ///< URDF joints welded at 0 (not actuated)
  std::string actuators_path;  ///< actuators.yaml
  ActuatorTable actuators;     ///< nominal drive models, loaded from actuators_path

  // ---- where the arm stands: gravity in the world frame and the placement in the world of the
  // base link (the body `base_link`; '' : the arm's root bodies, the URDF's root link or the
  // MJCF's bodies under <worldbody>); a robot bundle's frames.base, gravity_m_s2 and
  // base_placement, which the controller's model gets too. The arm's root bodies move as one so
  // that the base lands at base_placement, whatever fixed links lie between them and the base
  // (a body with a joint there is refused: the base is fixed in the world).
  std::string base_link;
  Eigen::Vector3d gravity_m_s2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  Eigen::Isometry3d base_placement = Eigen::Isometry3d::Identity();

  // ---- home posture: a simulated arm starts there at rest (holding it in Position mode); a
  // backend on a real arm takes it as the reference for continuous joints' turns
  std::vector<double> initial_q_rad;  ///< one per joint

  // ---- the end of arm: an F/T sensor at the flange and the tool below it, a tool alone on the
  // flange, or neither (a bare flange). Without a sensor there is no F/T sample ever
  // (RobotState::wrench never valid). A plant YAML has one when it gives the `ft_sensor` and
  // `tool` sections, or `tool` alone (with its flange_site); no default describes a particular arm.
  bool has_end_of_arm = false;
  bool has_ft_sensor = true;  ///< with has_end_of_arm: false for a tool on the flange, no sensor
  /// An F/T sensor is there to be read (external_torque_source ft or fused needs one).
  bool ft_sensor_present() const { return has_end_of_arm && has_ft_sensor; }
  struct FtSensor {
    /// MJCF site of the tool flange (z out of the flange), where the end of arm mounts (the tool
    /// itself when there is no sensor)
    std::string flange_site;
    /// The sensor's measuring frame in the flange site's frame (EndOfArm::sensor_mount): the
    /// tool body's pose on the adapter, its origin the sensor site.
    Eigen::Isometry3d sensor_mount = Eigen::Isometry3d::Identity();
    double flange_side_mass_kg = 0.0;  ///< not measured by the sensor
    Eigen::Vector3d flange_side_com_m = Eigen::Vector3d::Zero();  ///< flange frame
    Eigen::Vector3d flange_side_inertia_kgm2 = Eigen::Vector3d::Zero();
    /// The sensor's sample rate; the noise and bias below are what the simulator adds to its samples.
    double rate_Hz = 1000.0;
    double force_std_N = 0.05;
    double torque_std_Nm = 0.002;
    Eigen::Vector3d force_bias_N = Eigen::Vector3d::Zero();
    Eigen::Vector3d torque_bias_Nm = Eigen::Vector3d::Zero();
  } ft_sensor;

  // ---- the tool below the F/T sensor
  struct Tool {
    double mass_kg = 0.0;
    Eigen::Vector3d com_m = Eigen::Vector3d::Zero();         ///< sensor frame
    Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d::Zero();  ///< principal, sensor axes
  } tool;

  /// The end of arm's bodies (nullopt: a bare flange), and the same the other way; the flange
  /// site and the sensor's rate, noise and bias are left as they are.
  std::optional<EndOfArm> end_of_arm() const;
  void set_end_of_arm(const std::optional<EndOfArm>& end_of_arm);

  /// Bodies welded into links of the arm (a robot bundle's `payloads`), each a child body of the
  /// link's body with its inertial; none by default. A link that is no body of the arm's MJCF is
  /// a ConfigError at "payloads[i].link".
  std::vector<LinkPayload> payloads;

  // ---- whose drives: Kinova's loops, emulated (KinovaDriveEmulator, the `vendor` section), or a
  // generic current/torque drive (GenericDrive: a PD position hold with generic_hold's gains, no
  // integrator; plain torque; current). The plant YAML's `drive:` (default kinova) or a robot
  // bundle's, which must agree when both say it (RobotBundle::apply_to).
  DriveKind drive = DriveKind::kKinova;
  bool drive_stated = false;  ///< the plant YAML has a `drive:` key
  GenericHoldGains generic_hold;  ///< drive generic: the hold's gains (empty: GenericDrive::hold_gains' rule)
};

}  // namespace phri
