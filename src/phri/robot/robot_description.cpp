#include <phri/robot/robot_description.hpp>

#include <phri/core/yaml_reader.hpp>

namespace phri {

DriveKind parse_drive(const YamlReader& drive, int dof, GenericHoldGains& hold) {
  hold = GenericHoldGains{};
  if (!drive.is_map()) {
    const std::string text = drive.as_text();
    if (text == "kinova") return DriveKind::kKinova;
    if (text == "generic") return DriveKind::kGeneric;
    throw drive.error("", "'" + text + "': one of kinova, generic (or a map {kind, position_hold})");
  }
  drive.allow_keys({"kind", "position_hold"});
  const DriveKind kind = drive.choice("kind", {"kinova", "generic"}) == "generic" ? DriveKind::kGeneric : DriveKind::kKinova;
  if (!drive.has("position_hold")) return kind;
  if (kind != DriveKind::kGeneric) {
    throw drive.error("position_hold", "a generic drive's key; the kinova drive's position servo is the plant's vendor.position");
  }
  const YamlReader h = drive.at("position_hold");
  h.allow_keys({"kp_Nm_per_rad", "kd_Nms_per_rad"});
  if (h.has("kp_Nm_per_rad")) hold.kp_Nm_per_rad = h.per_joint("kp_Nm_per_rad", dof, kMinHoldKp_Nm_per_rad, kMaxHoldKp_Nm_per_rad);
  if (h.has("kd_Nms_per_rad")) hold.kd_Nms_per_rad = h.per_joint("kd_Nms_per_rad", dof, 0.0, kMaxHoldKd_Nms_per_rad);
  return kind;
}

std::optional<EndOfArm> RobotDescription::end_of_arm() const {
  if (!has_end_of_arm) return std::nullopt;
  EndOfArm e;
  e.has_ft_sensor = has_ft_sensor;
  if (!has_ft_sensor) {
    e.tool = {tool.mass_kg, tool.com_m, tool.inertia_kgm2};
    return e;
  }
  e.sensor_mount = ft_sensor.sensor_mount;
  e.flange_side = {ft_sensor.flange_side_mass_kg, ft_sensor.flange_side_com_m, ft_sensor.flange_side_inertia_kgm2};
  e.tool = {tool.mass_kg, tool.com_m, tool.inertia_kgm2};
  return e;
}

void RobotDescription::set_end_of_arm(const std::optional<EndOfArm>& end_of_arm) {
  has_end_of_arm = end_of_arm.has_value();
  const EndOfArm e = end_of_arm.value_or(EndOfArm{});
  has_ft_sensor = e.has_ft_sensor;
  const bool sensor = has_end_of_arm && has_ft_sensor;
  ft_sensor.sensor_mount = sensor ? e.sensor_mount : Eigen::Isometry3d::Identity();
  ft_sensor.flange_side_mass_kg = sensor ? e.flange_side.mass_kg : 0.0;
  ft_sensor.flange_side_com_m = e.flange_side.com_m;
  ft_sensor.flange_side_inertia_kgm2 = e.flange_side.principal_inertia_kgm2;
  tool.mass_kg = e.tool.mass_kg;
  tool.com_m = e.tool.com_m;
  tool.inertia_kgm2 = e.tool.principal_inertia_kgm2;
}

}  // namespace phri
