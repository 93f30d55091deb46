#pragma once
// phri::Model: the immutable description of a serial arm, built from a URDF (Pinocchio-style
// Model/Data split: algorithms take `(const Model&, Data&)`, see algorithms.hpp).
//
//   phri::Model model = phri::Model::from_urdf_file("robots/kinova_gen3/gen3.urdf");
//   phri::Data data(model);                      // all buffers, sized once
//   phri::compute_all_terms(model, data, q, qd); // FK, velocities, M, h, drift accelerations
//   const int ee = model.frame_id("end_effector_link");
//   phri::frame_jacobian(model, data, ee, phri::ReferenceFrame::kLocalWorldAligned, J);
//
// The chain runs from a base link (fixed in the world) to a tip link. Fixed joints are merged into
// their parent body; every link keeps a frame. Joint i moves body i; body i's parent is body i-1
// (body -1 is the base).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>
#include <string>
#include <vector>

namespace phri {

enum class JointType { kRevolute, kContinuous, kPrismatic };

/// Rigid-body inertia: mass, centre of mass and rotational inertia about the centre of mass,
/// both expressed in the frame that owns it.
struct Inertia {
  double mass = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_com = Eigen::Matrix3d::Zero();

  /// This inertia plus `other`, both expressed in the same frame (parallel-axis theorem).
  Inertia combined_with(const Inertia& other) const;
  /// The same body expressed in a frame where this frame has placement `placement`.
  Inertia transformed(const Eigen::Isometry3d& placement) const;
};

struct Joint {
  std::string name;
  JointType type = JointType::kRevolute;
  /// Unit axis in the joint frame (which is also the child body frame).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  /// Placement of the joint frame (at q = 0) in the parent body frame.
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
  double lower = -std::numeric_limits<double>::infinity();  // rad or m; infinite when unbounded
  double upper = std::numeric_limits<double>::infinity();
  double velocity_limit = std::numeric_limits<double>::infinity();  // rad/s or m/s
  double effort_limit = std::numeric_limits<double>::infinity();    // N.m or N
  /// Reflected rotor inertia added to the diagonal of M (kg.m^2); 0 unless set in ModelOptions.
  double armature = 0.0;
  bool has_position_limits() const { return lower > -std::numeric_limits<double>::infinity(); }
};

enum class FrameType { kLink, kExtra };

struct Frame {
  std::string name;
  FrameType type = FrameType::kLink;
  int body = -1;  ///< body the frame is fixed to; -1 for the base
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();  ///< in that body's frame
};

/// A frame the user adds to the model, fixed to an existing frame.
struct ExtraFrame {
  std::string name;
  std::string parent_frame;
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
};

/// A rigid payload fixed to a frame (a tool, an F/T sensor), merged into that frame's body.
struct Payload {
  std::string name;
  std::string frame;
  Inertia inertia;  ///< mass, centre of mass and inertia about it, in `frame`
};

struct ModelOptions {
  std::string base_link;  ///< empty: the URDF root link
  std::string tip_link;   ///< empty: the end of the chain of movable joints below the base
  /// Movable joints outside base -> tip (e.g. gripper fingers) are errors unless listed here;
  /// listed joints are treated as fixed at position 0 and their links merged.
  std::vector<std::string> locked_joints;
  std::vector<ExtraFrame> extra_frames;
  /// Payloads added to the bodies (what the URDF does not carry: sensor, tool).
  std::vector<Payload> payloads;
  /// Reflected rotor inertia per chain joint (empty: none).
  std::vector<double> armature;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< in the world frame
  /// Placement of the base link in the world.
  Eigen::Isometry3d base_placement = Eigen::Isometry3d::Identity();
};

class Model {
public:
  /// Loads a URDF file. Throws phri::ConfigError naming the file and the element on bad input.
  static Model from_urdf_file(const std::string& path, const ModelOptions& options = {});
  /// Loads a URDF from a string; `source_name` is used in error messages.
  static Model from_urdf_string(const std::string& urdf, const ModelOptions& options = {},
                                const std::string& source_name = "<urdf string>");

  const std::string& name() const { return name_; }
  int nq() const { return static_cast<int>(joints_.size()); }
  int nv() const { return nq(); }
  int num_bodies() const { return nq(); }
  int num_frames() const { return static_cast<int>(frames_.size()); }

  const std::vector<Joint>& joints() const { return joints_; }
  const Joint& joint(int i) const { return joints_[static_cast<std::size_t>(i)]; }
  /// Inertia of body i (its link and every link merged into it) in the body frame.
  const Inertia& body_inertia(int i) const { return bodies_[static_cast<std::size_t>(i)]; }
  const std::vector<Frame>& frames() const { return frames_; }
  const Frame& frame(int id) const { return frames_[static_cast<std::size_t>(id)]; }
  /// Frame index by name; throws ConfigError when unknown (use at start-up, not in the cycle).
  int frame_id(const std::string& name) const;
  bool has_frame(const std::string& name) const;
  /// Joint index by name; throws ConfigError when unknown.
  int joint_id(const std::string& name) const;

  const std::string& base_link() const { return base_link_; }
  const std::string& tip_link() const { return tip_link_; }
  const Eigen::Vector3d& gravity() const { return gravity_; }
  const Eigen::Isometry3d& base_placement() const { return base_placement_; }

  Eigen::VectorXd lower_limits() const;
  Eigen::VectorXd upper_limits() const;
  Eigen::VectorXd velocity_limits() const;
  Eigen::VectorXd effort_limits() const;
  double total_mass() const;  ///< of the moving bodies (the base excluded)
  /// What the loader accepted but the user should know, one line each, naming the link: urdfdom's
  /// warnings, inertias that violate the triangle inequality, an invalid inertial on a link fixed
  /// to the base (ignored). Empty for a clean file.
  const std::vector<std::string>& warnings() const { return warnings_; }

private:
  friend class UrdfModelBuilder;
  Model() = default;

  std::string name_;
  std::string base_link_;
  std::string tip_link_;
  std::vector<Joint> joints_;
  std::vector<Inertia> bodies_;
  std::vector<Frame> frames_;
  Eigen::Vector3d gravity_ = Eigen::Vector3d(0.0, 0.0, -9.81);
  Eigen::Isometry3d base_placement_ = Eigen::Isometry3d::Identity();
  std::vector<std::string> warnings_;
};

}  // namespace phri
