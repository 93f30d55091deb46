#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/sim_scene.hpp>
#include <phri/sim/urdf_plant.hpp>

#include <mujoco/mujoco.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace phri {
namespace {

// Digits that write a double back exactly.
std::string num(double v) { return format_general(v, 17); }

std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

std::string read_mjcf_text(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(file, "", "cannot open the MJCF file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (is_blank(buffer.str())) throw ConfigError(file, "", "the MJCF file is empty (expected a <mujoco> model)");
  return buffer.str();
}

// The arm alone: the MJCF file, or the one generated from the URDF.
std::string arm_text(const SimRobotConfig& config) {
  if (!config.mjcf_path.empty()) return read_mjcf_text(config.mjcf_path);
  UrdfPlantOptions options;
  options.urdf_path = config.urdf_path;
  options.locked_joints = config.locked_joints;
  options.balance_inertia = config.balance_inertia;
  options.timestep_s = config.physics_step_s();
  return UrdfPlant::generate(options).mjcf;
}

MjModelPtr load_arm(const SimRobotConfig& config) {
  std::string error;
  MjModelPtr arm = load_mjcf_text(arm_text(config), error);
  if (!arm) throw ConfigError(config.arm_file(), "", "MuJoCo cannot load it: " + error);
  return arm;
}

// Where the tool chain hangs: the flange site's body and the site's placement in it.
struct FlangeMount {
  std::string body;
  mjtNum pos[3];
  mjtNum quat[4];
};

// Loads the arm alone to find the flange and to check that it leaves the scene's names free.
FlangeMount find_flange_mount(const SimRobotConfig& config) {
  const std::string& file = config.arm_file();
  const MjModelPtr arm = load_arm(config);
  const std::string& site_name = config.ft_sensor.flange_site;
  const int site = mj_name2id(arm.get(), mjOBJ_SITE, site_name.c_str());
  if (site < 0) {
    throw ConfigError(config.source, config.has_ft_sensor ? "plant.ft_sensor.flange_site" : "plant.tool.flange_site",
                      "no site '" + site_name + "' in " + file);
  }
  FlangeMount mount;
  mount.body = mj_id2name(arm.get(), mjOBJ_BODY, arm->site_bodyid[site]);
  for (const char* name : {SimScene::kAdapterBody, SimScene::kToolBody, SimScene::kDropBody}) {
    if (mj_name2id(arm.get(), mjOBJ_BODY, name) >= 0) throw ConfigError(file, name, "body name reserved by the simulator scene");
  }
  for (const char* name : {SimScene::kSensorSite, SimScene::kAnchorSite}) {
    if (mj_name2id(arm.get(), mjOBJ_SITE, name) >= 0) throw ConfigError(file, name, "site name reserved by the simulator scene");
  }
  for (int k = 0; k < 3; ++k) mount.pos[k] = arm->site_pos[3 * site + k];
  for (int k = 0; k < 4; ++k) mount.quat[k] = arm->site_quat[4 * site + k];
  return mount;
}

void remove_keyframes(std::string& xml, const std::string& file) {
  const auto key_begin = xml.find("<keyframe");
  if (key_begin == std::string::npos) return;
  const auto key_end = xml.find("</keyframe>", key_begin);
  if (key_end == std::string::npos) throw ConfigError(file, "keyframe", "unterminated <keyframe>");
  xml.erase(key_begin, key_end + std::string("</keyframe>").size() - key_begin);
}

// The tool alone on the flange (no F/T sensor): its origin is the flange site's frame.
std::string bare_tool_mjcf(const SimRobotConfig& config, const FlangeMount& mount) {
  const std::string tool_contact = config.floor.enabled && config.floor.tool_contact ? "1" : "0";
  const mjtNum* sp = mount.pos;
  const mjtNum* sq = mount.quat;
  const auto& tool = config.tool;
  std::string chain;
  chain += "\n<!-- phri simulator scene: the tool on the flange (no F/T sensor) -->\n";
  chain += "<body name=\"" + std::string(SimScene::kToolBody) + "\" pos=\"" + num(sp[0]) + " " + num(sp[1]) + " " +
           num(sp[2]) + "\" quat=\"" + num(sq[0]) + " " + num(sq[1]) + " " + num(sq[2]) + " " + num(sq[3]) + "\">\n";
  chain += "  <inertial pos=\"" + vec(tool.com_m) + "\" mass=\"" + num(tool.mass_kg) + "\" diaginertia=\"" +
           vec(tool.inertia_kgm2) + "\"/>\n";
  chain += "  <geom name=\"" + std::string(SimScene::kToolGeom) + "\" type=\"box\" size=\"0.03 0.05 0.03\" pos=\"" + vec(tool.com_m) +
           "\" contype=\"" + tool_contact + "\" conaffinity=\"" + tool_contact +
           "\" group=\"1\" rgba=\"0.2 0.2 0.8 0.6\"/>\n";
  if (config.drop_test.enabled) {
    chain += "  <site name=\"" + std::string(SimScene::kAnchorSite) + "\" pos=\"" + vec(config.drop_test.anchor_m) +
             "\" size=\"0.005\"/>\n";
  }
  chain += "</body>\n";
  return chain;
}

// A turned sensor mount as an MJCF quat attribute; none for a straight one (MuJoCo's identity).
std::string mount_quat(const Eigen::Isometry3d& mount) {
  if (mount.linear() == Eigen::Matrix3d::Identity()) return "";
  const Eigen::Quaterniond q(mount.linear());
  return " quat=\"" + num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z()) + "\"";
}

// The F/T adapter and the tool below it, as a body tree for the flange body.
std::string tool_chain_mjcf(const SimRobotConfig& config, const FlangeMount& mount) {
  const std::string tool_contact = config.floor.enabled && config.floor.tool_contact ? "1" : "0";
  const mjtNum* sp = mount.pos;
  const mjtNum* sq = mount.quat;
  const auto& ft = config.ft_sensor;
  const auto& tool = config.tool;
  std::string chain;
  chain += "\n<!-- phri simulator scene: F/T adapter and sensor (flange side) -->\n";
  chain += "<body name=\"" + std::string(SimScene::kAdapterBody) + "\" pos=\"" + num(sp[0]) + " " + num(sp[1]) + " " +
           num(sp[2]) + "\" quat=\"" + num(sq[0]) + " " + num(sq[1]) + " " + num(sq[2]) + " " + num(sq[3]) + "\">\n";
  chain += "  <inertial pos=\"" + vec(ft.flange_side_com_m) + "\" mass=\"" + num(ft.flange_side_mass_kg) +
           "\" diaginertia=\"" + vec(ft.flange_side_inertia_kgm2) + "\"/>\n";
  const Eigen::Vector3d at = ft.sensor_mount.translation();
  const double half = 0.5 * std::max(at.z(), 1e-3);  // the adapter's look only (no contact, no mass)
  chain += "  <geom name=\"ft_adapter_geom\" type=\"cylinder\" size=\"0.04 " + num(half) + "\" pos=\"0 0 " + num(half) +
           "\" contype=\"0\" conaffinity=\"0\" group=\"1\" rgba=\"0.3 0.3 0.35 0.6\"/>\n";
  chain += "  <!-- the tool (below the sensor): its origin is the sensor's measuring frame -->\n";
  chain += "  <body name=\"" + std::string(SimScene::kToolBody) + "\" pos=\"" + vec(at) + "\"" + mount_quat(ft.sensor_mount) + ">\n";
  chain += "    <inertial pos=\"" + vec(tool.com_m) + "\" mass=\"" + num(tool.mass_kg) + "\" diaginertia=\"" +
           vec(tool.inertia_kgm2) + "\"/>\n";
  chain += "    <geom name=\"" + std::string(SimScene::kToolGeom) + "\" type=\"box\" size=\"0.03 0.05 0.03\" pos=\"" + vec(tool.com_m) +
           "\" contype=\"" + tool_contact + "\" conaffinity=\"" + tool_contact +
           "\" group=\"1\" rgba=\"0.2 0.2 0.8 0.6\"/>\n";
  chain += "    <site name=\"" + std::string(SimScene::kSensorSite) + "\" size=\"0.01\"/>\n";
  if (config.drop_test.enabled) {
    chain += "    <site name=\"" + std::string(SimScene::kAnchorSite) + "\" pos=\"" + vec(config.drop_test.anchor_m) +
             "\" size=\"0.005\"/>\n";
  }
  chain += "  </body>\n</body>\n";
  return chain;
}

// `text` right after the start tag of <body name="`body`">.
void insert_into_body(std::string& xml, const std::string& body, const std::string& text, const std::string& file) {
  std::size_t pos = 0;
  std::size_t insert_at = std::string::npos;
  const std::string needle = "name=\"" + body + "\"";
  while ((pos = xml.find(needle, pos)) != std::string::npos) {
    const auto tag = xml.rfind('<', pos);
    if (tag != std::string::npos && xml.compare(tag, 5, "<body") == 0) {
      const auto close = xml.find('>', pos);
      if (close == std::string::npos || xml[close - 1] == '/') {
        throw ConfigError(file, body, "flange body tag not found or self-closing");
      }
      insert_at = close + 1;
      break;
    }
    pos += needle.size();
  }
  if (insert_at == std::string::npos) throw ConfigError(file, body, "cannot find the flange <body> tag");
  xml.insert(insert_at, text);
}

// The drop-test mass, held at the cable anchor until release.
std::string drop_mass_mjcf(const SimRobotConfig& config) {
  const auto& d = config.drop_test;
  const double I = 0.4 * d.mass_kg * d.radius_m * d.radius_m;  // solid sphere
  const char* collide = config.floor.enabled ? "1" : "0";
  std::string body;
  body += "<!-- phri simulator scene: drop-test mass (held at the cable anchor until release) -->\n";
  body += "<body name=\"" + std::string(SimScene::kDropBody) + "\" pos=\"0 0 0\">\n";
  body += "  <freejoint name=\"drop_mass_free\"/>\n";
  body += "  <inertial pos=\"0 0 0\" mass=\"" + num(d.mass_kg) + "\" diaginertia=\"" + num(I) + " " + num(I) + " " +
          num(I) + "\"/>\n";
  body += "  <geom name=\"drop_mass_geom\" type=\"sphere\" size=\"" + num(d.radius_m) + "\" contype=\"" + collide +
          "\" conaffinity=\"" + collide + "\" group=\"1\" rgba=\"0.8 0.3 0.2 1\"/>\n";
  body += "</body>\n";
  return body;
}

// What the scene adds to the world body: the drop mass and the floor, when enabled.
std::string world_additions_mjcf(const SimRobotConfig& config) {
  std::string world;
  if (config.drop_test.enabled) world += drop_mass_mjcf(config);
  if (config.floor.enabled) {
    world += "<geom name=\"" + std::string(SimScene::kFloorGeom) + "\" type=\"plane\" size=\"5 5 0.1\" pos=\"0 0 " +
             num(config.floor.height_m) + "\" contype=\"1\" conaffinity=\"1\" group=\"0\" rgba=\"0.6 0.6 0.6 1\"/>\n";
  }
  return world;
}

// The F/T sensor pair, one <sensor> section.
std::string ft_sensors_mjcf() {
  return "<sensor>\n  <force name=\"" + std::string(SimScene::kForceSensor) + "\" site=\"" + SimScene::kSensorSite +
         "\"/>\n  <torque name=\"" + std::string(SimScene::kTorqueSensor) + "\" site=\"" + SimScene::kSensorSite +
         "\"/>\n</sensor>\n";
}

// `text` before the last closing tag of `element` (e.g. </worldbody>).
void insert_before_end_tag(std::string& xml, const std::string& element, const std::string& text,
                           const std::string& file) {
  const std::string end_tag = "</" + element + ">";
  const auto end = xml.rfind(end_tag);
  if (end == std::string::npos) throw ConfigError(file, element, "no " + end_tag);
  xml.insert(end, text);
}

// The bodies a robot bundle's `payloads` fix to links: each a child body of its link's body, at the
// link's frame, with the payload's inertial (no geometry, no contact). Links that are no body of
// the arm, and names the arm already uses, are refused naming the payload.
std::vector<std::pair<std::string, std::string>> payload_bodies(const SimRobotConfig& config) {
  std::vector<std::pair<std::string, std::string>> out;  // (link, MJCF text)
  if (config.payloads.empty()) return out;
  const MjModelPtr arm = load_arm(config);
  for (std::size_t i = 0; i < config.payloads.size(); ++i) {
    const LinkPayload& p = config.payloads[i];
    const std::string key = "payloads[" + std::to_string(i) + "]";
    if (mj_name2id(arm.get(), mjOBJ_BODY, p.link.c_str()) < 0) {
      throw ConfigError(config.source, key + ".link", "no body '" + p.link + "' in the arm's plant (" + config.arm_file() + ")");
    }
    const std::string name = std::string(SimScene::kPayloadBodyPrefix) + p.name;
    if (mj_name2id(arm.get(), mjOBJ_BODY, name.c_str()) >= 0) {
      throw ConfigError(config.source, key + ".name", "body name '" + name + "' already used by the arm's plant");
    }
    if (!(p.body.mass_kg > 0.0) || !(p.body.principal_inertia_kgm2.array() > 0.0).all() || !p.body.com_m.allFinite()) {
      throw ConfigError(config.source, key, "needs a mass > 0, principal moments > 0 and a finite COM");
    }
    out.emplace_back(p.link, "\n<!-- phri simulator scene: payload '" + p.name + "' on " + p.link + " -->\n<body name=\"" + name +
                                 "\">\n  <inertial pos=\"" + vec(p.body.com_m) + "\" mass=\"" + num(p.body.mass_kg) +
                                 "\" diaginertia=\"" + vec(p.body.principal_inertia_kgm2) + "\"/>\n</body>\n");
  }
  return out;
}

}  // namespace

std::string SimScene::build_mjcf(const SimRobotConfig& config) {
  const std::string& file = config.arm_file();
  std::string xml = arm_text(config);
  remove_keyframes(xml, file);
  if (config.has_end_of_arm) {
    const FlangeMount mount = find_flange_mount(config);
    insert_into_body(xml, mount.body, config.has_ft_sensor ? tool_chain_mjcf(config, mount) : bare_tool_mjcf(config, mount), file);
  }
  for (const auto& [link, body] : payload_bodies(config)) insert_into_body(xml, link, body, file);
  insert_before_end_tag(xml, "worldbody", world_additions_mjcf(config), file);
  if (config.ft_sensor_present()) insert_before_end_tag(xml, "mujoco", ft_sensors_mjcf(), file);
  return xml;
}

std::vector<SimScene::ArmJoint> SimScene::arm_joints(const SimRobotConfig& config) {
  const std::string& file = config.arm_file();
  const MjModelPtr arm = load_arm(config);
  std::vector<ArmJoint> out;
  for (const ActuatorParameters& a : config.actuators.joints()) {
    const int j = mj_name2id(arm.get(), mjOBJ_JOINT, a.joint_name.c_str());
    if (j < 0) throw ConfigError(file, a.joint_name, "joint of actuators.yaml missing in the MJCF");
    ArmJoint joint;
    joint.name = a.joint_name;
    joint.hinge = arm->jnt_type[j] == mjJNT_HINGE;
    joint.limited = arm->jnt_limited[j] != 0;
    joint.lower = arm->jnt_range[2 * j];
    joint.upper = arm->jnt_range[2 * j + 1];
    out.push_back(joint);
  }
  return out;
}

}  // namespace phri
