#pragma once
// Random serial chains written twice, as a URDF and as an equivalent MJCF, from the same numbers:
// the MJCF side uses MuJoCo's own parsing of euler angles ("XYZ" = URDF roll-pitch-yaw), of
// inertias (diaginertia + frame, or fullinertia) and its own merging of welded bodies, so that
// comparing phri with MuJoCo on these tests phri's URDF handling as well as its algorithms.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace phri::test {

struct RandomChain {
  std::string urdf;
  std::string mjcf;
  int dof = 0;
  std::vector<std::string> link_names;  ///< every link, base first
  std::string tip_link;
};

/// dof movable joints (revolute, continuous, prismatic) with random axes, origins and inertias;
/// some fixed links with mass in between, and a fixed massless tool frame at the end.
inline RandomChain make_random_chain(int dof, std::mt19937& rng, double armature_max = 0.0,
                                     std::vector<double>* armature_out = nullptr) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto num = [](double x) {
    std::ostringstream s;
    s.precision(17);
    s << x;
    return s.str();
  };
  auto vec3 = [&](const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); };
  auto random_rpy = [&]() { return Eigen::Vector3d(M_PI * unit(rng), 0.5 * M_PI * unit(rng), M_PI * unit(rng)); };
  auto random_axis = [&]() -> Eigen::Vector3d {
    if (u01(rng) < 0.4) {  // axis-aligned, as most real arms
      Eigen::Vector3d a = Eigen::Vector3d::Zero();
      a[static_cast<int>(u01(rng) * 3) % 3] = u01(rng) < 0.5 ? -1.0 : 1.0;
      return a;
    }
    Eigen::Vector3d a(unit(rng), unit(rng), unit(rng));
    return a.normalized();
  };

  RandomChain out;
  out.dof = dof;
  std::ostringstream urdf;
  std::ostringstream mjcf;
  urdf << "<?xml version=\"1.0\"?>\n<robot name=\"random_chain\">\n";
  mjcf << "<mujoco model=\"random_chain\">\n"
       << "  <compiler angle=\"radian\" eulerseq=\"XYZ\" inertiafromgeom=\"false\"/>\n"
       << "  <option gravity=\"0 0 -9.81\"/>\n  <worldbody>\n";

  // Inertial of one link: either principal moments in a rotated frame or a full tensor.
  auto inertial = [&](std::ostringstream& u, std::ostringstream& m, const std::string& indent) {
    const double mass = 0.2 + 3.0 * u01(rng);
    const Eigen::Vector3d box(0.05 + 0.3 * u01(rng), 0.05 + 0.3 * u01(rng), 0.05 + 0.3 * u01(rng));
    const Eigen::Vector3d moments(mass / 12.0 * (box.y() * box.y() + box.z() * box.z()),
                                  mass / 12.0 * (box.x() * box.x() + box.z() * box.z()),
                                  mass / 12.0 * (box.x() * box.x() + box.y() * box.y()));
    const Eigen::Vector3d com(0.15 * unit(rng), 0.15 * unit(rng), 0.15 * unit(rng));
    if (u01(rng) < 0.5) {
      const Eigen::Vector3d rpy = random_rpy();
      u << indent << "<inertial><origin xyz=\"" << vec3(com) << "\" rpy=\"" << vec3(rpy) << "\"/><mass value=\""
        << num(mass) << "\"/><inertia ixx=\"" << num(moments.x()) << "\" ixy=\"0\" ixz=\"0\" iyy=\""
        << num(moments.y()) << "\" iyz=\"0\" izz=\"" << num(moments.z()) << "\"/></inertial>\n";
      m << indent << "<inertial pos=\"" << vec3(com) << "\" euler=\"" << vec3(rpy) << "\" mass=\"" << num(mass)
        << "\" diaginertia=\"" << vec3(moments) << "\"/>\n";
    } else {
      const Eigen::Matrix3d r =
          Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()).toRotationMatrix();
      const Eigen::Matrix3d t = r * moments.asDiagonal() * r.transpose();
      u << indent << "<inertial><origin xyz=\"" << vec3(com) << "\" rpy=\"0 0 0\"/><mass value=\"" << num(mass)
        << "\"/><inertia ixx=\"" << num(t(0, 0)) << "\" ixy=\"" << num(t(0, 1)) << "\" ixz=\"" << num(t(0, 2))
        << "\" iyy=\"" << num(t(1, 1)) << "\" iyz=\"" << num(t(1, 2)) << "\" izz=\"" << num(t(2, 2))
        << "\"/></inertial>\n";
      // MuJoCo gets the principal frame (MuJoCo's own fullinertia diagonalisation is only ~1e-10
      // accurate, see tools/mjcf_principal_inertia.py); the URDF gets the full tensor.
      const Eigen::Quaterniond qr(r);
      m << indent << "<inertial pos=\"" << vec3(com) << "\" mass=\"" << num(mass) << "\" quat=\"" << num(qr.w())
        << " " << num(qr.x()) << " " << num(qr.y()) << " " << num(qr.z()) << "\" diaginertia=\"" << vec3(moments)
        << "\"/>\n";
    }
  };

  urdf << "  <link name=\"base\"/>\n";
  out.link_names.push_back("base");
  mjcf << "    <body name=\"base\">\n";
  std::string indent = "      ";
  std::string parent = "base";
  int depth = 1;
  int fixed_count = 0;
  if (armature_out) armature_out->clear();
  for (int i = 0; i < dof; ++i) {
    // Sometimes a fixed link with its own mass before the next movable joint.
    if (u01(rng) < 0.25) {
      const std::string name = "fixed_" + std::to_string(fixed_count++);
      const Eigen::Vector3d xyz(0.2 * unit(rng), 0.2 * unit(rng), 0.2 * unit(rng));
      const Eigen::Vector3d rpy = random_rpy();
      std::ostringstream fixed_inertial_urdf, fixed_inertial_mjcf;
      inertial(fixed_inertial_urdf, fixed_inertial_mjcf, indent + "  ");
      urdf << "  <link name=\"" << name << "\">\n" << fixed_inertial_urdf.str() << "  </link>\n";
      urdf << "  <joint name=\"" << name << "_joint\" type=\"fixed\"><parent link=\"" << parent
           << "\"/><child link=\"" << name << "\"/><origin xyz=\"" << vec3(xyz) << "\" rpy=\"" << vec3(rpy)
           << "\"/></joint>\n";
      mjcf << indent << "<body name=\"" << name << "\" pos=\"" << vec3(xyz) << "\" euler=\"" << vec3(rpy) << "\">\n";
      mjcf << fixed_inertial_mjcf.str();
      indent += "  ";
      ++depth;
      parent = name;
      out.link_names.push_back(name);
    }
    const std::string link = "link_" + std::to_string(i + 1);
    const std::string joint = "joint_" + std::to_string(i + 1);
    const double pick = u01(rng);
    const std::string type = pick < 0.55 ? "revolute" : pick < 0.8 ? "continuous" : "prismatic";
    const Eigen::Vector3d xyz(0.3 * unit(rng), 0.3 * unit(rng), 0.3 * unit(rng));
    const Eigen::Vector3d rpy = random_rpy();
    const Eigen::Vector3d axis = random_axis();
    const double armature = armature_max * u01(rng);
    if (armature_out) armature_out->push_back(armature);

    std::ostringstream link_inertial_urdf, link_inertial_mjcf;
    inertial(link_inertial_urdf, link_inertial_mjcf, indent + "  ");
    urdf << "  <link name=\"" << link << "\">\n" << link_inertial_urdf.str() << "  </link>\n";
    urdf << "  <joint name=\"" << joint << "\" type=\"" << type << "\"><parent link=\"" << parent
         << "\"/><child link=\"" << link << "\"/><origin xyz=\"" << vec3(xyz) << "\" rpy=\"" << vec3(rpy)
         << "\"/><axis xyz=\"" << vec3(axis) << "\"/>";
    if (type != "continuous") urdf << "<limit lower=\"-3\" upper=\"3\" effort=\"50\" velocity=\"2\"/>";
    urdf << "</joint>\n";
    mjcf << indent << "<body name=\"" << link << "\" pos=\"" << vec3(xyz) << "\" euler=\"" << vec3(rpy) << "\">\n";
    mjcf << link_inertial_mjcf.str();
    mjcf << indent << "  <joint name=\"" << joint << "\" type=\"" << (type == "prismatic" ? "slide" : "hinge")
         << "\" axis=\"" << vec3(axis) << "\" armature=\"" << num(armature) << "\"/>\n";
    indent += "  ";
    ++depth;
    parent = link;
    out.link_names.push_back(link);
  }
  // A massless tool frame, as end_effector_link on real arms.
  const Eigen::Vector3d tool_xyz(0.1 * unit(rng), 0.1 * unit(rng), 0.1 + 0.1 * u01(rng));
  const Eigen::Vector3d tool_rpy = random_rpy();
  urdf << "  <link name=\"tool\"/>\n  <joint name=\"tool_joint\" type=\"fixed\"><parent link=\"" << parent
       << "\"/><child link=\"tool\"/><origin xyz=\"" << vec3(tool_xyz) << "\" rpy=\"" << vec3(tool_rpy)
       << "\"/></joint>\n";
  mjcf << indent << "<body name=\"tool\" pos=\"" << vec3(tool_xyz) << "\" euler=\"" << vec3(tool_rpy)
       << "\"/>\n";
  out.link_names.push_back("tool");
  out.tip_link = "tool";
  for (int d = depth; d >= 1; --d) {
    indent.resize(indent.size() - 2);
    mjcf << indent << "</body>\n";
  }
  urdf << "</robot>\n";
  mjcf << "  </worldbody>\n</mujoco>\n";
  out.urdf = urdf.str();
  out.mjcf = mjcf.str();
  return out;
}

}  // namespace phri::test
