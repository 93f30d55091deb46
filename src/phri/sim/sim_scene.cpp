#include <phri/core/error.hpp>
#include <phri/sim/sim_scene.hpp>

#include <mujoco/mujoco.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

namespace phri {
namespace {

std::string num(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", v);
  return buffer;
}

std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};

}  // namespace

std::string SimScene::build_mjcf(const SimRobotConfig& config) {
  const std::string& file = config.mjcf_path;
  std::ifstream in(file);
  if (!in) throw ConfigError(file, "", "cannot open the MJCF file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string xml = buffer.str();

  // The arm alone, to find the flange and check names.
  char error[1024] = "";
  std::unique_ptr<mjModel, ModelDeleter> arm(mj_loadXML(file.c_str(), nullptr, error, sizeof(error)));
  if (!arm) throw ConfigError(file, "", std::string("MuJoCo cannot load it: ") + error);
  const std::string& site_name = config.ft_sensor.flange_site;
  const int site = mj_name2id(arm.get(), mjOBJ_SITE, site_name.c_str());
  if (site < 0) throw ConfigError(config.source, "plant.ft_sensor.flange_site", "no site '" + site_name + "' in " + file);
  const int flange = arm->site_bodyid[site];
  const std::string flange_body = mj_id2name(arm.get(), mjOBJ_BODY, flange);
  for (const char* name : {kAdapterBody, kToolBody, kDropBody}) {
    if (mj_name2id(arm.get(), mjOBJ_BODY, name) >= 0) throw ConfigError(file, name, "body name reserved by the simulator scene");
  }
  for (const char* name : {kSensorSite, kAnchorSite}) {
    if (mj_name2id(arm.get(), mjOBJ_SITE, name) >= 0) throw ConfigError(file, name, "site name reserved by the simulator scene");
  }
  const mjtNum* sp = arm->site_pos + 3 * site;
  const mjtNum* sq = arm->site_quat + 4 * site;

  // Remove the keyframes.
  const auto key_begin = xml.find("<keyframe");
  if (key_begin != std::string::npos) {
    const auto key_end = xml.find("</keyframe>", key_begin);
    if (key_end == std::string::npos) throw ConfigError(file, "keyframe", "unterminated <keyframe>");
    xml.erase(key_begin, key_end + std::string("</keyframe>").size() - key_begin);
  }

  // Tool chain inside the flange body, right after its start tag.
  const auto& ft = config.ft_sensor;
  const auto& tool = config.tool;
  std::string chain;
  chain += "\n<!-- phri simulator scene: F/T adapter and sensor (flange side) -->\n";
  chain += "<body name=\"" + std::string(kAdapterBody) + "\" pos=\"" + num(sp[0]) + " " + num(sp[1]) + " " + num(sp[2]) +
           "\" quat=\"" + num(sq[0]) + " " + num(sq[1]) + " " + num(sq[2]) + " " + num(sq[3]) + "\">\n";
  chain += "  <inertial pos=\"" + vec(ft.flange_side_com_m) + "\" mass=\"" + num(ft.flange_side_mass_kg) +
           "\" diaginertia=\"" + vec(ft.flange_side_inertia_kgm2) + "\"/>\n";
  const double half = 0.5 * std::max(ft.sensor_offset_m, 1e-3);
  chain += "  <geom name=\"ft_adapter_geom\" type=\"cylinder\" size=\"0.04 " + num(half) + "\" pos=\"0 0 " + num(half) +
           "\" contype=\"0\" conaffinity=\"0\" group=\"1\" rgba=\"0.3 0.3 0.35 0.6\"/>\n";
  chain += "  <!-- the tool (below the sensor): its origin is the sensor's measuring frame -->\n";
  chain += "  <body name=\"" + std::string(kToolBody) + "\" pos=\"0 0 " + num(ft.sensor_offset_m) + "\">\n";
  chain += "    <inertial pos=\"" + vec(tool.com_m) + "\" mass=\"" + num(tool.mass_kg) + "\" diaginertia=\"" +
           vec(tool.inertia_kgm2) + "\"/>\n";
  chain += "    <geom name=\"tool_geom\" type=\"box\" size=\"0.03 0.05 0.03\" pos=\"" + vec(tool.com_m) +
           "\" contype=\"0\" conaffinity=\"0\" group=\"1\" rgba=\"0.2 0.2 0.8 0.6\"/>\n";
  chain += "    <site name=\"" + std::string(kSensorSite) + "\" size=\"0.01\"/>\n";
  if (config.drop_test.enabled) {
    chain += "    <site name=\"" + std::string(kAnchorSite) + "\" pos=\"" + vec(config.drop_test.anchor_m) + "\" size=\"0.005\"/>\n";
  }
  chain += "  </body>\n</body>\n";

  std::size_t pos = 0;
  std::size_t insert_at = std::string::npos;
  const std::string needle = "name=\"" + flange_body + "\"";
  while ((pos = xml.find(needle, pos)) != std::string::npos) {
    const auto tag = xml.rfind('<', pos);
    if (tag != std::string::npos && xml.compare(tag, 5, "<body") == 0) {
      const auto close = xml.find('>', pos);
      if (close == std::string::npos || xml[close - 1] == '/') {
        throw ConfigError(file, flange_body, "flange body tag not found or self-closing");
      }
      insert_at = close + 1;
      break;
    }
    pos += needle.size();
  }
  if (insert_at == std::string::npos) throw ConfigError(file, flange_body, "cannot find the flange <body> tag");
  xml.insert(insert_at, chain);

  // World additions.
  std::string world;
  if (config.drop_test.enabled) {
    const auto& d = config.drop_test;
    const double I = 0.4 * d.mass_kg * d.radius_m * d.radius_m;  // solid sphere
    const char* collide = config.floor.enabled ? "1" : "0";
    world += "<!-- phri simulator scene: drop-test mass (held at the cable anchor until release) -->\n";
    world += "<body name=\"" + std::string(kDropBody) + "\" pos=\"0 0 0\">\n";
    world += "  <freejoint name=\"drop_mass_free\"/>\n";
    world += "  <inertial pos=\"0 0 0\" mass=\"" + num(d.mass_kg) + "\" diaginertia=\"" + num(I) + " " + num(I) + " " +
             num(I) + "\"/>\n";
    world += "  <geom name=\"drop_mass_geom\" type=\"sphere\" size=\"" + num(d.radius_m) + "\" contype=\"" + collide +
             "\" conaffinity=\"" + collide + "\" group=\"1\" rgba=\"0.8 0.3 0.2 1\"/>\n";
    world += "</body>\n";
  }
  if (config.floor.enabled) {
    world += "<geom name=\"" + std::string(kFloorGeom) + "\" type=\"plane\" size=\"5 5 0.1\" pos=\"0 0 " +
             num(config.floor.height_m) + "\" contype=\"1\" conaffinity=\"1\" group=\"0\" rgba=\"0.6 0.6 0.6 1\"/>\n";
  }
  const auto world_end = xml.rfind("</worldbody>");
  if (world_end == std::string::npos) throw ConfigError(file, "worldbody", "no </worldbody>");
  xml.insert(world_end, world);

  // F/T sensors (one <sensor> section appended before </mujoco>).
  std::string sensors = "<sensor>\n  <force name=\"" + std::string(kForceSensor) + "\" site=\"" + kSensorSite +
                        "\"/>\n  <torque name=\"" + std::string(kTorqueSensor) + "\" site=\"" + kSensorSite +
                        "\"/>\n</sensor>\n";
  const auto end = xml.rfind("</mujoco>");
  if (end == std::string::npos) throw ConfigError(file, "mujoco", "no </mujoco>");
  xml.insert(end, sensors);
  return xml;
}

}  // namespace phri
