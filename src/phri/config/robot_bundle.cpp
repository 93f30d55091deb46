#include <phri/config/robot_bundle.hpp>
#include <phri/config/physical_ranges.hpp>

#include <phri/core/format.hpp>
#include <phri/core/rpy.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/control/controller.hpp>
#include <phri/model/capsule_fit.hpp>
#include <phri/model/model.hpp>
#include <phri/robot/actuator_table.hpp>

#include <Eigen/Eigenvalues>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

namespace phri {
namespace {

// What an arm carries at its flange: physical_ranges.hpp; its COM within 0.5 m of its frame, an
// adapter not a boom (0.5 m).
using physical_range::kMaxJointAngle_rad;
using physical_range::kMaxPayload_kg;
using physical_range::kMaxPayloadInertia_kgm2;
// A dead band hides model error (~1 N.m), not a push: 10 N.m is already a firm push at the wrist.
constexpr double kMaxDeadband_Nm = 10.0;

std::string input_file(const YamlReader& r, std::string_view key, const std::string& folder) {
  const std::string text = r.text(key);
  if (text.empty()) throw r.error(key, "empty file name");
  const std::string path = resolve_path(folder, text, PathForm::kAbsolute);
  if (!std::filesystem::is_regular_file(path)) throw r.error(key, "file not found: " + path);
  return path;
}

std::vector<std::string> names(const YamlReader& r, std::string_view key) {
  std::vector<std::string> out;
  if (!r.has(key)) return out;
  const YamlReader list = r.at(key);
  list.expect_sequence();
  for (std::size_t i = 0; i < list.size(); ++i) out.push_back(list.at(i).as_text());
  return out;
}

// mass_kg, com_m (within max_com_m of the frame on each axis), inertia_kgm2 (principal moments).
RigidBodyData rigid_body_values(const YamlReader& r, double max_com_m) {
  RigidBodyData body;
  body.mass_kg = r.number("mass_kg", 0.0, kMaxPayload_kg);
  if (!(body.mass_kg > 0.0)) throw r.error("mass_kg", "must be > 0");
  body.com_m = r.vector3("com_m", -max_com_m, max_com_m);
  body.principal_inertia_kgm2 = r.vector3("inertia_kgm2", 1e-9, kMaxPayloadInertia_kgm2);
  const Eigen::Vector3d& i = body.principal_inertia_kgm2;
  if (i[0] + i[1] < i[2] || i[0] + i[2] < i[1] || i[1] + i[2] < i[0]) {
    throw r.error("inertia_kgm2", "principal moments must satisfy the triangle inequality (a rigid body)");
  }
  return body;
}

RigidBodyData rigid_body(const YamlReader& r) {
  r.allow_keys({"mass_kg", "com_m", "inertia_kgm2"});
  return rigid_body_values(r, 0.5);
}

// `payloads`: [{name (optional), link, mass_kg, com_m, inertia_kgm2}, ...], in the link's frame. A
// body on a link (a camera on the forearm, a valve block on the shoulder) sits within 1 m of the
// link's frame; its mass and moments within what an arm carries (physical_ranges.hpp). Whether
// the link exists is checked against the URDF's model (check_against_model).
std::vector<LinkPayload> parse_payloads(const YamlReader& list) {
  list.expect_sequence();
  std::vector<LinkPayload> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader p = list.at(i);
    p.allow_keys({"name", "link", "mass_kg", "com_m", "inertia_kgm2"});
    LinkPayload payload;
    payload.name = p.text_or("name", "payload_" + std::to_string(i));
    if (payload.name.empty()) throw p.error("name", "empty name");
    for (const LinkPayload& other : out) {
      if (other.name == payload.name) throw p.error("name", "duplicate payload name '" + payload.name + "'");
    }
    payload.link = p.text("link");
    payload.body = rigid_body_values(p, 1.0);
    out.push_back(payload);
  }
  return out;
}

void parse_frames(const YamlReader& f, RobotBundle& b) {
  f.allow_keys({"base", "tip", "end_effector"});
  b.base_link = f.text_or("base", "");
  b.tip_link = f.text_or("tip", "");
  b.end_effector_frame = f.text("end_effector");
}

// Gravity: finite, at most 3 g (more is a unit mistake; 0 is an arm in orbit, allowed).
Eigen::Vector3d parse_gravity(const YamlReader& r) {
  const Eigen::Vector3d g = r.vector3("gravity_m_s2", -30.0, 30.0);
  if (!(g.norm() <= 30.0)) throw r.error("gravity_m_s2", "|g| = " + format_general(g.norm(), 6) + " m/s^2: at most 30 (3 g)");
  return g;
}

// The base link in the world: within 10 m of the origin, angles within a turn.
Eigen::Isometry3d parse_base_placement(const YamlReader& b) {
  b.allow_keys({"xyz_m", "rpy_rad"});
  const Eigen::Vector3d xyz = b.vector3_or("xyz_m", Eigen::Vector3d::Zero(), -10.0, 10.0);
  const Eigen::Vector3d rpy = b.vector3_or("rpy_rad", Eigen::Vector3d::Zero(), -kMaxJointAngle_rad, kMaxJointAngle_rad);
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
  placement.translation() = xyz;
  placement.linear() = rpy_rotation(rpy);
  return placement;
}

// `end_of_arm: none` (or no key): a bare flange; `tool` alone: a tool on the flange, no F/T sensor.
std::optional<EndOfArm> parse_end_of_arm(const YamlReader& e) {
  if (e.node().IsScalar()) {
    if (e.as_text() != "none") throw e.error("", "a map (ft_sensor, tool) or `none`");
    return std::nullopt;
  }
  e.allow_keys({"ft_sensor", "tool"});
  EndOfArm end;
  end.has_ft_sensor = e.has("ft_sensor");
  if (end.has_ft_sensor) {
    const YamlReader sensor = e.at("ft_sensor");
    sensor.allow_keys({"offset_m", "xyz_m", "rpy_rad", "flange_side"});
    end.sensor_mount = read_sensor_mount(sensor, "offset_m", "xyz_m", "rpy_rad");
    end.flange_side = rigid_body(sensor.at("flange_side"));
  }
  end.tool = rigid_body(e.at("tool"));
  return end;
}

void parse_plant(const YamlReader& p, const std::string& folder, RobotBundle& b) {
  p.allow_keys({"mjcf", "flange_site", "balance_inertia"});
  if (p.has("mjcf")) b.plant.mjcf_path = input_file(p, "mjcf", folder);
  // A generated plant has a site at every link frame: the end-effector frame's by default.
  b.plant.flange_site = p.has("mjcf") ? p.text("flange_site") : p.text_or("flange_site", b.end_effector_frame);
  b.plant.balance_inertia = p.boolean_or("balance_inertia", false);
  if (p.has("mjcf") && p.has("balance_inertia")) {
    throw p.error("balance_inertia", "applies to a plant generated from the URDF only (no 'mjcf')");
  }
}

// H(z) = b(z^-1) / a(z^-1): finite, a0 != 0, order at most 5, every pole inside the unit circle
// (the loop runs it on the torque error every period: an unstable filter would run away).
void parse_custom_loop_filter(const YamlReader& f, RobotBundle& b) {
  f.allow_keys({"numerator", "denominator"});
  for (const char* key : {"numerator", "denominator"}) {
    const YamlReader list = f.at(key);
    list.expect_sequence();
    if (list.size() < 1 || list.size() > 6) throw f.error(key, "1 to 6 coefficients (order at most 5)");
    auto& out = std::string(key) == "numerator" ? b.custom_loop_numerator : b.custom_loop_denominator;
    for (std::size_t i = 0; i < list.size(); ++i) out.push_back(list.at(i).as_number(-1e6, 1e6));
  }
  const std::vector<double>& a = b.custom_loop_denominator;
  if (a[0] == 0.0) throw f.error("denominator", "a0 must be non-zero");
  const int order = static_cast<int>(a.size()) - 1;
  if (order == 0) return;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(order, order);  // poles: its eigenvalues
  for (int k = 0; k < order; ++k) companion(0, k) = -a[static_cast<std::size_t>(k + 1)] / a[0];
  for (int k = 1; k < order; ++k) companion(k, k - 1) = 1.0;
  const double largest = Eigen::EigenSolver<Eigen::MatrixXd>(companion, false).eigenvalues().cwiseAbs().maxCoeff();
  // A margin for the eigenvalues' rounding: a double pole at z = 1 comes out within ~1e-8 of it.
  if (!(largest < 1.0 - 1e-6)) {
    throw f.error("denominator", "a pole at |z| = " + format_general(largest, 6) + ": every pole must lie inside the unit circle");
  }
}

RobotBundle parse(const YamlReader& r, const std::string& folder) {
  r.allow_keys({"name", "urdf", "actuators", "collision", "frames", "locked_joints", "home_q_rad",
                "compliance_deadband_Nm", "drive", "custom_loop_filter", "end_of_arm", "payloads", "plant",
                "gravity_m_s2", "base_placement"});
  RobotBundle b;
  b.source = r.file();
  b.name = r.text("name");
  b.urdf_path = input_file(r, "urdf", folder);
  b.actuators_path = input_file(r, "actuators", folder);
  const bool fitted = r.has("collision") && r.text("collision") == "fitted";
  b.collision_path = r.has("collision") && !fitted ? input_file(r, "collision", folder) : "";
  if (fitted) b.collision_yaml = "fitted";  // fitted once the model is checked (check_against_model)
  parse_frames(r.at("frames"), b);
  if (r.has("gravity_m_s2")) b.gravity_m_s2 = parse_gravity(r);
  if (r.has("base_placement")) b.base_placement = parse_base_placement(r.at("base_placement"));
  b.locked_joints = names(r, "locked_joints");
  const int dof = ActuatorTable::from_yaml_file(b.actuators_path).size();
  b.home_q_rad = r.per_joint<std::vector<double>>("home_q_rad", dof, -kMaxJointAngle_rad, kMaxJointAngle_rad);
  // Absent: the controller's default per drive (by `size`, or 1 % of the torque limit without one).
  if (r.has("compliance_deadband_Nm")) {
    b.compliance_deadband_Nm = r.per_joint<Eigen::VectorXd>("compliance_deadband_Nm", dof, 0.0, kMaxDeadband_Nm);
  }
  b.drive = parse_drive(r.at("drive"), dof, b.generic_hold);
  if (r.has("custom_loop_filter")) parse_custom_loop_filter(r.at("custom_loop_filter"), b);
  if (r.has("end_of_arm")) b.end_of_arm = parse_end_of_arm(r.at("end_of_arm"));
  if (r.has("payloads")) b.payloads = parse_payloads(r.at("payloads"));
  parse_plant(r.has("plant") ? r.at("plant") : YamlReader(YAML::Node(YAML::NodeType::Map), r.file(), "plant"), folder, b);
  return b;
}

// The chain's problems named at the robot.yaml key that causes them (the loader names ModelOptions).
[[noreturn]] void rethrow_at_key(const RobotBundle& b, const ConfigError& e) {
  const std::string& element = e.element();
  const std::string what = e.reason() + " (" + e.file() + ")";
  if (element.find("tip_link") != std::string::npos) throw ConfigError(b.source, "frames.tip", what);
  if (element.find("base_link") != std::string::npos) throw ConfigError(b.source, "frames.base", what);
  if (element.find("locked_joints") != std::string::npos || e.reason().find("locked_joints") != std::string::npos) {
    throw ConfigError(b.source, "locked_joints", element + ": " + what);
  }
  throw e;
}

// The frames, the chain, the drives and the home posture against the URDF's model.
void check_against_model(const RobotBundle& b) {
  ModelOptions chain;
  chain.base_link = b.base_link;
  chain.tip_link = b.tip_link;
  chain.locked_joints = b.locked_joints;
  std::optional<Model> loaded;
  try {
    loaded.emplace(Model::from_urdf_file(b.urdf_path, chain));
  } catch (const ConfigError& e) {
    rethrow_at_key(b, e);
  }
  const Model& model = *loaded;
  if (!model.has_frame(b.end_effector_frame)) {
    throw ConfigError(b.source, "frames.end_effector", "no frame '" + b.end_effector_frame + "' in " + b.urdf_path);
  }
  for (std::size_t i = 0; i < b.payloads.size(); ++i) {
    const std::string& link = b.payloads[i].link;
    if (!model.has_frame(link)) {
      throw ConfigError(b.source, "payloads[" + std::to_string(i) + "].link",
                        "no link '" + link + "' in the arm's model (" + b.urdf_path + ")");
    }
  }
  const ActuatorTable drives = ActuatorTable::from_yaml_file(b.actuators_path);
  if (b.drive == DriveKind::kKinova) {
    drives.require_stated(b.actuators_path, "drive: kinova (" + b.source + ") emulates Kinova's loops on the motor data");
  }
  for (int i = 0; i < model.nq(); ++i) {
    if (i >= drives.size() || drives[i].joint_name != model.joint(i).name) {
      throw ConfigError(b.source, "actuators", "entry " + std::to_string(i + 1) + " must be the chain's joint '" +
                                                   model.joint(i).name + "' (" + b.actuators_path + ")");
    }
    const double q = b.home_q_rad[static_cast<std::size_t>(i)];
    if (q < model.joint(i).lower || q > model.joint(i).upper) {
      throw ConfigError(b.source, "home_q_rad[" + std::to_string(i) + "]",
                        format_general(q, 6) + " is beyond " + model.joint(i).name + "'s limits [" +
                            format_general(model.joint(i).lower, 6) + ", " + format_general(model.joint(i).upper, 6) + "]");
    }
  }
  if (drives.size() != model.nq()) {
    throw ConfigError(b.source, "actuators", std::to_string(drives.size()) + " drives for the chain's " +
                                                 std::to_string(model.nq()) + " joints");
  }
}

// `collision: fitted`: the capsules on the controller's model (chain and payload frames).
std::string fitted_capsules(const RobotBundle& b) {
  ControllerSettings settings;
  b.apply_to(settings);
  const Model model = Model::from_urdf_file(b.urdf_path, Controller::model_options(settings));
  std::ifstream file(b.urdf_path);
  std::stringstream urdf;
  urdf << file.rdbuf();
  const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(b.home_q_rad.data(), model.nq());
  // Pairs within the self-collision damper's influence distance at home would be held apart at rest.
  CapsuleFitOptions options;
  options.clearance_m = WholeBodyQpSettings{}.collision.influence_distance;
  return fit_capsules(urdf.str(), model, home, options).yaml;
}

}  // namespace

RobotBundle RobotBundle::from_folder(const std::string& folder) {
  const std::string file = (std::filesystem::path(folder) / "robot.yaml").string();
  if (!std::filesystem::is_regular_file(file)) throw ConfigError(file, "", "no robot.yaml in the robot folder");
  RobotBundle bundle = parse(YamlReader::load_file(file), std::filesystem::absolute(folder).string());
  check_against_model(bundle);
  if (!bundle.collision_yaml.empty()) bundle.collision_yaml = fitted_capsules(bundle);
  return bundle;
}

void RobotBundle::apply_to(ControllerSettings& s) const {
  s.urdf_path = urdf_path;
  s.actuators_path = actuators_path;
  s.collision_path = collision_path;
  s.collision_yaml = collision_yaml;
  s.base_link = base_link;
  s.tip_link = tip_link;
  s.end_effector_frame = end_effector_frame;
  s.locked_joints = locked_joints;
  s.qp.compliance_deadband = compliance_deadband_Nm;
  s.set_end_of_arm(end_of_arm);
  for (const LinkPayload& p : payloads) {  // after the end of arm's, which set_end_of_arm replaces
    s.payloads.push_back(ControllerSettings::end_of_arm_payload(p.name.c_str(), p.body));
    s.payloads.back().frame = p.link;
  }
  s.gravity_m_s2 = gravity_m_s2;
  s.base_placement = base_placement;
  s.custom_torque.filter_numerator = custom_loop_numerator;
  s.custom_torque.filter_denominator = custom_loop_denominator;
  if (drive != DriveKind::kKinova && custom_loop_numerator.empty()) {
    // Kinova's H(z) was identified on Kinova's actuators: another drive gets no filter term unless
    // its bundle states one (the loop is then the feed-forward and the leaky integrator).
    s.custom_torque.filter_numerator = {0.0};
    s.custom_torque.filter_denominator = {1.0};
  }
  s.offered_loops = offered_loops(drive);
}

void RobotBundle::apply_to(SimRobotConfig& c) const {
  c.mjcf_path = plant.mjcf_path;
  c.urdf_path = plant.mjcf_path.empty() ? urdf_path : "";
  c.locked_joints = plant.mjcf_path.empty() ? locked_joints : std::vector<std::string>{};
  c.balance_inertia = plant.balance_inertia;
  c.actuators_path = actuators_path;
  c.actuators = ActuatorTable::from_yaml_file(actuators_path);
  if (c.initial_q_rad.size() != home_q_rad.size()) c.initial_q_rad = home_q_rad;
  c.ft_sensor.flange_site = plant.flange_site;
  c.set_end_of_arm(end_of_arm);
  c.payloads = payloads;
  c.base_link = base_link;
  c.gravity_m_s2 = gravity_m_s2;
  c.base_placement = base_placement;
  // A plant that says which drives it emulates must say the robot's: a Kinova emulation under an
  // arm whose drives are generic (or the reverse) would run loops the robot does not have.
  if (c.drive_stated && c.drive != drive) {
    throw ConfigError(c.source, "plant.drive", "the plant emulates " + std::string(to_string(c.drive)) +
                                                   " drives, the robot's are " + std::string(to_string(drive)) +
                                                   " (drive in " + source + "): they must agree");
  }
  c.drive = drive;
  // The hold's gains the plant states are the simulated drive's (as actuator_overrides); else the robot's.
  if (c.generic_hold.kp_Nm_per_rad.empty()) c.generic_hold.kp_Nm_per_rad = generic_hold.kp_Nm_per_rad;
  if (c.generic_hold.kd_Nms_per_rad.empty()) c.generic_hold.kd_Nms_per_rad = generic_hold.kd_Nms_per_rad;
}

}  // namespace phri
