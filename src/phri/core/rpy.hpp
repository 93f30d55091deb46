#pragma once
// Roll-pitch-yaw as a URDF <origin rpy> means it: R = Rz(yaw) Ry(pitch) Rx(roll), about fixed
// axes. The one place phri turns rpy into a rotation (a robot bundle's base_placement, an F/T
// sensor's mount on the flange), so that every such key means the URDF's convention.
#include <Eigen/Geometry>

namespace phri {

inline Eigen::Matrix3d rpy_rotation(const Eigen::Vector3d& rpy_rad) {
  return (Eigen::AngleAxisd(rpy_rad.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy_rad.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy_rad.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace phri
