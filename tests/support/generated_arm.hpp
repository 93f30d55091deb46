#pragma once
// Arms the project generates itself (issue 16), as URDF text: random link lengths and lateral
// offsets, twists alternating +-90 degrees (an anthropomorphic arm, non-degenerate), inertials
// with rotated principal frames and COM offsets, a fixed tool mount with mass, a massless flange
// frame at the end, optionally one prismatic joint and a gripper branch whose two finger joints
// the controller and the plant lock. Its drives: the Gen3's actuators.yaml entries (large ones on
// the first half of the joints, small ones after), renamed.
#include <phri/robot/actuator_table.hpp>

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace phri::test {

struct ArmSpec {
  int dof = 6;
  int prismatic_joint = -1;  ///< index of the joint that is prismatic; -1: none
  bool gripper = false;
  unsigned seed = 1;
};

struct GeneratedArm {
  std::string urdf;
  std::vector<std::string> joints;         ///< chain joints, base first
  std::vector<std::string> locked_joints;  ///< the gripper's fingers
  std::vector<double> home_q;              ///< a bent start posture
  std::string flange = "flange";           ///< end-effector frame (massless, end of the chain)
  std::string elbow_link;                  ///< a link near the middle, for pushes
};

inline GeneratedArm make_arm(const ArmSpec& spec) {
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  auto num = [](double x) {
    std::ostringstream s;
    s.precision(17);
    s << x;
    return s.str();
  };
  // A link of `mass` whose body runs from its origin to `next` (cylinder of radius r along it),
  // principal frame rotated at random (the URDF carries it as inertial rpy).
  auto inertial = [&](double mass, const Eigen::Vector3d& next) {
    const double length = std::max(next.norm(), 0.05), r = 0.04;
    const double axial = 0.5 * mass * r * r, transverse = mass * (3.0 * r * r + length * length) / 12.0;
    const Eigen::Vector3d com = 0.5 * next + Eigen::Vector3d(0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng));
    std::ostringstream s;
    s << "<inertial><origin xyz=\"" << num(com.x()) << " " << num(com.y()) << " " << num(com.z()) << "\" rpy=\""
      << num(M_PI * u(rng)) << " " << num(0.5 * M_PI * u(rng)) << " " << num(M_PI * u(rng)) << "\"/><mass value=\""
      << num(mass) << "\"/><inertia ixx=\"" << num(transverse) << "\" ixy=\"0\" ixz=\"0\" iyy=\"" << num(transverse)
      << "\" iyz=\"0\" izz=\"" << num(axial) << "\"/></inertial>";
    return s.str();
  };
  GeneratedArm arm;
  std::ostringstream urdf;
  urdf << "<?xml version=\"1.0\"?>\n<robot name=\"generated_" << spec.dof << "dof\">\n";
  // The origin of each joint in its parent link: up the parent's z (first joint) or along its y.
  std::vector<Eigen::Vector3d> origins;
  for (int i = 0; i <= spec.dof; ++i) {
    const double length = 0.12 + 0.12 * u01(rng);
    const Eigen::Vector3d lateral(0.03 * u(rng), 0.0, 0.03 * u(rng));
    origins.push_back(i == 0 ? Eigen::Vector3d(0, 0, 0.15) : Eigen::Vector3d(lateral.x(), -length, lateral.z()));
  }
  urdf << "<link name=\"base_link\">" << inertial(2.0, origins[0]) << "</link>\n";
  std::string parent = "base_link";
  for (int i = 0; i < spec.dof; ++i) {
    const std::string link = "link_" + std::to_string(i + 1), joint = "joint_" + std::to_string(i + 1);
    const double mass = 1.6 - 1.0 * i / std::max(1, spec.dof - 1);
    const bool prismatic = i == spec.prismatic_joint;
    const double twist = i == 0 ? 0.0 : (i % 2 == 1 ? 0.5 * M_PI : -0.5 * M_PI);
    urdf << "<link name=\"" << link << "\">" << inertial(mass, origins[static_cast<std::size_t>(i + 1)]) << "</link>\n";
    urdf << "<joint name=\"" << joint << "\" type=\"" << (prismatic ? "prismatic" : "revolute") << "\"><parent link=\""
         << parent << "\"/><child link=\"" << link << "\"/><origin xyz=\"" << num(origins[i].x()) << " "
         << num(origins[i].y()) << " " << num(origins[i].z()) << "\" rpy=\"" << num(twist) << " 0 0\"/><axis xyz=\"0 0 1\"/>"
         << (prismatic ? "<limit lower=\"-0.05\" upper=\"0.15\" effort=\"80\" velocity=\"0.5\"/>"
                       : "<limit lower=\"-2.6\" upper=\"2.6\" effort=\"40\" velocity=\"1.4\"/>")
         << "</joint>\n";
    arm.joints.push_back(joint);
    arm.home_q.push_back(prismatic ? 0.05 : (i % 2 == 1 ? 0.5 + 0.2 * u(rng) : 0.3 * u(rng)));
    parent = link;
  }
  arm.elbow_link = "link_" + std::to_string((spec.dof + 1) / 2);
  // A fixed tool mount with its mass (a fixed tool in the URDF), then the massless flange.
  const Eigen::Vector3d& end = origins.back();
  urdf << "<link name=\"tool_mount\">" << inertial(0.25, Eigen::Vector3d(0, 0, 0.05)) << "</link>\n"
       << "<joint name=\"tool_mount_joint\" type=\"fixed\"><parent link=\"" << parent << "\"/><child link=\"tool_mount\"/>"
       << "<origin xyz=\"" << num(end.x()) << " " << num(end.y()) << " " << num(end.z()) << "\" rpy=\"1.5707963267948966 0 0\"/></joint>\n"
       << "<link name=\"flange\"/><joint name=\"flange_joint\" type=\"fixed\"><parent link=\"tool_mount\"/>"
       << "<child link=\"flange\"/><origin xyz=\"0 0 0.06\"/></joint>\n";
  if (spec.gripper) {
    urdf << "<link name=\"gripper_body\">" << inertial(0.4, Eigen::Vector3d(0, 0.05, 0)) << "</link>\n"
         << "<joint name=\"gripper_mount\" type=\"fixed\"><parent link=\"tool_mount\"/><child link=\"gripper_body\"/>"
         << "<origin xyz=\"0 0.04 0.03\"/></joint>\n";
    for (const char* side : {"left", "right"}) {
      const std::string finger = std::string(side) + "_finger";
      urdf << "<link name=\"" << finger << "\">" << inertial(0.05, Eigen::Vector3d(0, 0.03, 0)) << "</link>\n"
           << "<joint name=\"" << finger << "_joint\" type=\"prismatic\"><parent link=\"gripper_body\"/><child link=\""
           << finger << "\"/><origin xyz=\"" << (side[0] == 'l' ? "0.02" : "-0.02") << " 0.08 0\"/><axis xyz=\"1 0 0\"/>"
           << "<limit lower=\"0\" upper=\"0.04\" effort=\"20\" velocity=\"0.1\"/></joint>\n";
      arm.locked_joints.push_back(finger + "_joint");
    }
  }
  urdf << "</robot>\n";
  arm.urdf = urdf.str();
  return arm;
}

/// The Gen3's drives on the arm's joints: large ones on the first half, small ones after.
inline ActuatorTable drives_for(const GeneratedArm& arm, const ActuatorTable& gen3) {
  std::vector<ActuatorParameters> joints;
  const int n = static_cast<int>(arm.joints.size());
  for (int i = 0; i < n; ++i) {
    ActuatorParameters a = gen3[i < (n + 1) / 2 ? 0 : gen3.size() - 1];
    a.joint_name = arm.joints[static_cast<std::size_t>(i)];
    joints.push_back(a);
  }
  return ActuatorTable(std::move(joints));
}

}  // namespace phri::test
