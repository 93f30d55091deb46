#include <phri/core/format.hpp>
#include <phri/core/rpy.hpp>
#include <phri/core/yaml_reader.hpp>
#include <phri/robot/end_of_arm.hpp>

#include <numbers>
#include <string>

namespace phri {

Eigen::Isometry3d read_sensor_mount(const YamlReader& sensor, std::string_view offset_key, std::string_view xyz_key,
                                    std::string_view rpy_key) {
  constexpr double kMaxReach_m = 0.5;  // an adapter, not a boom
  constexpr double kTurn_rad = 2.0 * std::numbers::pi;  // beyond a turn: degrees written for radians
  if (sensor.has(offset_key) && sensor.has(xyz_key)) {
    throw sensor.error(xyz_key, "give " + std::string(offset_key) + " (along the flange z) or " + std::string(xyz_key) +
                                    ", not both");
  }
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  if (sensor.has(xyz_key)) {
    const Eigen::Vector3d xyz = sensor.vector3(xyz_key, -kMaxReach_m, kMaxReach_m);
    if (!(xyz.norm() <= kMaxReach_m)) {
      throw sensor.error(xyz_key, "|xyz| = " + format_general(xyz.norm(), 6) + " m: at most 0.5 (an adapter, not a boom)");
    }
    mount.translation() = xyz;
  } else {
    mount.translation().z() = sensor.number(offset_key, 0.0, kMaxReach_m);
  }
  // Left out, the rotation stays the exact identity (a straight mount's numbers do not move).
  if (sensor.has(rpy_key)) mount.linear() = rpy_rotation(sensor.vector3(rpy_key, -kTurn_rad, kTurn_rad));
  return mount;
}

}  // namespace phri
