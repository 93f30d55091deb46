// Model construction from URDF (urdfdom) with validation, and the small Model queries.
#include <phri/model/model.hpp>

#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/core/parser_lock.hpp>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <locale>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

namespace phri {

// ---------------------------------------------------------------------------------- Inertia
Inertia Inertia::combined_with(const Inertia& other) const {
  const double m = mass + other.mass;
  if (m <= 0.0) return Inertia{};
  Inertia out;
  out.mass = m;
  out.com = (mass * com + other.mass * other.com) / m;
  auto shifted = [&](const Inertia& part) -> Eigen::Matrix3d {
    const Eigen::Vector3d d = part.com - out.com;
    return part.inertia_com +
           part.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  };
  out.inertia_com = shifted(*this) + shifted(other);
  return out;
}

Inertia Inertia::transformed(const Eigen::Isometry3d& placement) const {
  Inertia out;
  out.mass = mass;
  out.com = placement * com;
  out.inertia_com = placement.linear() * inertia_com * placement.linear().transpose();
  return out;
}

// ---------------------------------------------------------------------------------- builder
namespace {

// Captures urdfdom's console_bridge messages. urdfdom 3 logs some failures and still returns a
// model: a mass written "0.73kg" logs "Could not parse inertial element for Link [...]" and leaves
// the mass at 0, so an error-level message is a load error even when parsing "succeeded".
// console_bridge's handler is global: loads hold urdf_parser_mutex().
class CapturingOutput : public console_bridge::OutputHandler {
public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      if (!errors.empty()) errors += "; ";
      errors += text;
    } else if (level == console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      warnings.push_back(text);
    }
  }
  std::string errors;
  std::vector<std::string> warnings;
};

bool finite(double x) { return std::isfinite(x); }

// Physical ranges of a link (the reason next to each).
// No link of a robot arm weighs a tonne (the Gen3's weigh 0.4 to 1.7 kg; an industrial arm's
// heaviest link ~100 kg): above is a unit mistake or a corrupted file (1e300).
constexpr double kMaxLinkMass_kg = 1000.0;
// Radius of gyration sqrt(I / m) at most 2 m: every point of an arm link lies within its reach.
constexpr double kMaxGyrationRadius_m = 2.0;
// A revolute joint's limits within one turn each way; a joint that turns freely is 'continuous'.
constexpr double kMaxRevoluteLimit_rad = 2.0 * 3.14159265358979323846;

Eigen::Isometry3d to_isometry(const urdf::Pose& pose) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond quat(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  out.linear() = quat.normalized().toRotationMatrix();
  out.translation() << pose.position.x, pose.position.y, pose.position.z;
  return out;
}

bool pose_is_finite(const urdf::Pose& p) {
  return finite(p.position.x) && finite(p.position.y) && finite(p.position.z) &&
         finite(p.rotation.x) && finite(p.rotation.y) && finite(p.rotation.z) && finite(p.rotation.w);
}

bool is_movable(const urdf::Joint& joint) { return joint.type != urdf::Joint::FIXED; }

// An <origin>'s numbers as written: urdfdom turns rpy into a quaternion, which is finite for any
// finite angle (1e308 rad included). One turn each way, with room for rounded 2 pi: beyond is a
// corrupted file or degrees typed as radians. No arm's frame lies 100 m from its parent.
constexpr double kMaxOriginAngle_rad = kMaxRevoluteLimit_rad + 0.01;
constexpr double kMaxOriginOffset_m = 100.0;
// <limit>: a joint speed of 100 rad/s (or m/s) and an effort of 1e5 N.m (or N) are beyond any arm's
// drive (an industrial arm's strongest joint: ~1e4 N.m); a prismatic travel within 100 m.
constexpr double kMaxLimitVelocity = 100.0;
constexpr double kMaxLimitEffort = 1e5;

// The value of attribute `name` in the tag text `tag` ("" when absent).
std::string attribute(const std::string& tag, const std::string& name) {
  for (std::size_t at = tag.find(name); at != std::string::npos; at = tag.find(name, at + 1)) {
    if (at == 0 || !std::isspace(static_cast<unsigned char>(tag[at - 1]))) continue;
    std::size_t i = tag.find_first_not_of(" \t\r\n", at + name.size());
    if (i == std::string::npos || tag[i] != '=') continue;
    i = tag.find_first_not_of(" \t\r\n", i + 1);
    if (i == std::string::npos || (tag[i] != '"' && tag[i] != '\'')) continue;
    const std::size_t end = tag.find(tag[i], i + 1);
    if (end != std::string::npos) return tag.substr(i + 1, end - i - 1);
  }
  return "";
}

// Every <origin> of the URDF text (comments skipped), named by its enclosing <joint> or <link>.
void check_origins(const std::string& urdf, const std::string& source) {
  std::string owner = "robot";
  for (std::size_t at = urdf.find('<'); at != std::string::npos; at = urdf.find('<', at + 1)) {
    if (urdf.compare(at, 4, "<!--") == 0) {
      at = urdf.find("-->", at);
      if (at == std::string::npos) return;  // urdfdom reports the broken comment
      continue;
    }
    const std::size_t end = urdf.find('>', at);
    if (end == std::string::npos) return;
    const std::string tag = urdf.substr(at, end - at);
    const std::string element = tag.substr(1, tag.find_first_of(" \t\r\n/") - 1);
    if (element == "joint" || element == "link") owner = element + " '" + attribute(tag, "name") + "'";
    if (element != "origin") continue;
    for (const char* key : {"xyz", "rpy"}) {
      std::istringstream values(attribute(tag, key));
      values.imbue(std::locale::classic());
      const bool angle = std::string(key) == "rpy";
      const double bound = angle ? kMaxOriginAngle_rad : kMaxOriginOffset_m;
      for (double v; values >> v;) {
        if (std::isfinite(v) && std::abs(v) <= bound) continue;
        throw ConfigError(source, owner + " <origin> " + key,
                          format_general(v, 6) + (angle ? " rad is beyond one turn (|angle| <= 2 pi; degrees typed as radians?)"
                                                        : " m is not a link offset (|offset| <= 100 m)"));
      }
    }
  }
}

}  // namespace

class UrdfModelBuilder {
public:
  UrdfModelBuilder(const urdf::ModelInterface& urdf, const ModelOptions& options, std::string source,
                   std::vector<std::string> parser_warnings)
      : urdf_(urdf), options_(options), source_(std::move(source)) {
    for (std::string& w : parser_warnings) model_.warnings_.push_back(source_ + ": " + w);
  }

  Model build() {
    model_.name_ = urdf_.getName();
    model_.gravity_ = options_.gravity;
    model_.base_placement_ = options_.base_placement;
    if (!options_.gravity.allFinite()) fail("ModelOptions.gravity", "must be finite");
    if (!options_.base_placement.matrix().allFinite()) fail("ModelOptions.base_placement", "must be finite");

    check_tree();
    const urdf::Link* base = resolve_base();
    model_.base_link_ = base->name;
    const urdf::Link* tip = resolve_tip(base);
    model_.tip_link_ = tip->name;

    // The links on the path base -> tip (base excluded), which decides what is "the chain".
    for (const urdf::Link* link = tip; link != base; link = link->getParent().get()) {
      on_path_[link->name] = true;
    }
    visit(*base, -1, Eigen::Isometry3d::Identity());

    if (model_.joints_.empty()) {
      fail("", "no movable joint between base '" + base->name + "' and tip '" + tip->name + "'");
    }
    check_base_fixed(*base);
    for (std::size_t i = 0; i < model_.bodies_.size(); ++i) check_body(static_cast<int>(i));
    add_extra_frames();
    add_payloads();
    apply_armature();
    for (const std::string& name : options_.locked_joints) {
      if (!urdf_.getJoint(name)) fail("ModelOptions.locked_joints", "unknown joint '" + name + "'");
    }
    return std::move(model_);
  }

private:
  [[noreturn]] void fail(const std::string& element, const std::string& reason) const {
    throw ConfigError(source_, element, reason);
  }

  // urdfdom 3 accepts kinematic loops (a link that is the child of two joints, a joint whose parent
  // is its child, a cycle of joints): the walks below would recurse or loop for ever on them.
  void check_tree() const {
    std::map<std::string, std::string> joint_of_child;
    for (const auto& [name, joint] : urdf_.joints_) {
      const std::string& child = joint->child_link_name;
      if (child == joint->parent_link_name) {
        fail("joint '" + name + "'", "its parent and child are the same link '" + child +
                                         "': a kinematic loop (a URDF describes a tree)");
      }
      const auto [it, inserted] = joint_of_child.emplace(child, name);
      if (!inserted) {
        fail("link '" + child + "'", "is the child of two joints ('" + it->second + "' and '" + name +
                                         "'): a kinematic loop (a URDF describes a tree)");
      }
    }
    // With one parent per link, a loop is a cycle of parents: no walk up may be longer than the tree.
    for (const auto& [name, link] : urdf_.links_) {
      std::size_t steps = 0;
      for (const urdf::Link* up = link.get(); up != nullptr; up = up->getParent().get()) {
        if (++steps > urdf_.links_.size()) {
          fail("link '" + name + "'", "its chain of parent joints comes back to itself: a kinematic loop "
                                      "(a URDF describes a tree)");
        }
      }
    }
  }

  // The model starts at the base, fixed in the world (at ModelOptions.base_placement): a joint that
  // moves between the URDF's root and the base would carry the base, and the model would be wrong.
  void check_base_fixed(const urdf::Link& base) const {
    for (const urdf::Link* link = &base; link->parent_joint; link = link->getParent().get()) {
      if (moves(*link->parent_joint)) {
        fail("ModelOptions.base_link", "joint '" + link->parent_joint->name + "' moves between the URDF's root '" +
                                           urdf_.getRoot()->name + "' and the base link '" + base.name +
                                           "': the base must be fixed in the world (lock that joint, or take the base at or above it)");
      }
    }
  }

  const urdf::Link* resolve_base() const {
    if (options_.base_link.empty()) {
      auto root = urdf_.getRoot();
      if (!root) fail("", "no root link");
      return root.get();
    }
    auto link = urdf_.getLink(options_.base_link);
    if (!link) fail("ModelOptions.base_link", "unknown link '" + options_.base_link + "'");
    return link.get();
  }

  bool locked(const std::string& joint) const {
    return std::find(options_.locked_joints.begin(), options_.locked_joints.end(), joint) !=
           options_.locked_joints.end();
  }
  bool moves(const urdf::Joint& joint) const { return is_movable(joint) && !locked(joint.name); }

  // True when the subtree below `link` contains a movable, unlocked joint.
  bool subtree_moves(const urdf::Link& link) const {
    for (const auto& joint : link.child_joints) {
      if (moves(*joint)) return true;
    }
    for (const auto& child : link.child_links) {
      if (subtree_moves(*child)) return true;
    }
    return false;
  }

  const urdf::Link* resolve_tip(const urdf::Link* base) const {
    if (!options_.tip_link.empty()) {
      auto tip = urdf_.getLink(options_.tip_link);
      if (!tip) fail("ModelOptions.tip_link", "unknown link '" + options_.tip_link + "'");
      const urdf::Link* link = tip.get();
      while (link != nullptr && link != base) link = link->getParent().get();
      if (link == nullptr) {
        fail("ModelOptions.tip_link", "link '" + options_.tip_link + "' is not below base '" + base->name + "'");
      }
      return tip.get();
    }
    // Follow the only branch that still moves; a fork means the user must choose.
    const urdf::Link* link = base;
    for (;;) {
      const urdf::Link* next = nullptr;
      for (std::size_t c = 0; c < link->child_links.size(); ++c) {
        const urdf::Link& child = *link->child_links[c];
        if (moves(*child.parent_joint) || subtree_moves(child)) {
          if (next != nullptr) {
            fail("link '" + link->name + "'",
                 "the tree branches here (toward '" + next->name + "' and '" + child.name +
                     "'); set ModelOptions.tip_link, and lock the other branch's joints");
          }
          next = &child;
        }
      }
      if (next == nullptr) return link;
      link = next;
    }
  }

  // Depth-first walk of the base subtree: assigns each link to a body and a placement in it.
  void visit(const urdf::Link& link, int body, const Eigen::Isometry3d& placement_in_body) {
    add_link_inertia(link, body, placement_in_body);
    model_.frames_.push_back(Frame{link.name, FrameType::kLink, body, placement_in_body});

    for (std::size_t c = 0; c < link.child_links.size(); ++c) {
      const urdf::Link& child = *link.child_links[c];
      const urdf::Joint& joint = *child.parent_joint;
      const std::string where = "joint '" + joint.name + "'";
      if (!pose_is_finite(joint.parent_to_joint_origin_transform)) fail(where, "origin is not finite");
      const Eigen::Isometry3d joint_in_body = placement_in_body * to_isometry(joint.parent_to_joint_origin_transform);
      if (!moves(joint)) {
        visit(child, body, joint_in_body);
        continue;
      }
      if (!on_path_.count(child.name)) {
        fail(where, "movable joint branches off the chain '" + model_.base_link_ + "' -> '" +
                        model_.tip_link_ + "'; add it to ModelOptions.locked_joints or choose another tip_link");
      }
      if (body != static_cast<int>(model_.joints_.size()) - 1) {
        fail(where, "internal error: chain bodies out of order");
      }
      model_.joints_.push_back(make_joint(joint, joint_in_body));
      model_.bodies_.push_back(Inertia{});
      visit(child, static_cast<int>(model_.joints_.size()) - 1, Eigen::Isometry3d::Identity());
    }
  }

  Joint make_joint(const urdf::Joint& urdf_joint, const Eigen::Isometry3d& placement) const {
    const std::string where = "joint '" + urdf_joint.name + "'";
    Joint joint;
    joint.name = urdf_joint.name;
    joint.placement = placement;
    switch (urdf_joint.type) {
      case urdf::Joint::REVOLUTE: joint.type = JointType::kRevolute; break;
      case urdf::Joint::CONTINUOUS: joint.type = JointType::kContinuous; break;
      case urdf::Joint::PRISMATIC: joint.type = JointType::kPrismatic; break;
      case urdf::Joint::FLOATING: fail(where, "floating joints are not supported in a serial arm");
      case urdf::Joint::PLANAR: fail(where, "planar joints are not supported in a serial arm");
      default: fail(where, "unknown joint type");
    }
    if (urdf_joint.mimic) fail(where, "mimic joints are not supported on the chain");
    const Eigen::Vector3d axis(urdf_joint.axis.x, urdf_joint.axis.y, urdf_joint.axis.z);
    if (!axis.allFinite() || axis.norm() < 1e-9) fail(where, "<axis> must be a finite non-zero vector");
    joint.axis = axis.normalized();
    if (const auto& limits = urdf_joint.limits) {
      const double values[] = {limits->lower, limits->upper, limits->velocity, limits->effort};
      for (double v : values) {
        if (!finite(v)) fail(where + " <limit>", "values must be finite");
      }
      if (limits->velocity < 0.0) fail(where + " <limit>", "velocity must be >= 0 (got " + format_general(limits->velocity, 6) + ")");
      if (limits->effort < 0.0) fail(where + " <limit>", "effort must be >= 0 (got " + format_general(limits->effort, 6) + ")");
      if (limits->velocity > kMaxLimitVelocity) {
        fail(where + " <limit>", "velocity " + format_general(limits->velocity, 6) + " is beyond any arm's joint (<= 100)");
      }
      if (limits->effort > kMaxLimitEffort) {
        fail(where + " <limit>", "effort " + format_general(limits->effort, 6) + " is beyond any arm's drive (<= 1e5)");
      }
      if (joint.type == JointType::kPrismatic &&
          std::max(std::abs(limits->lower), std::abs(limits->upper)) > kMaxOriginOffset_m) {
        fail(where + " <limit>", "prismatic limits [" + format_general(limits->lower, 6) + ", " +
                                     format_general(limits->upper, 6) + "] m reach beyond 100 m");
      }
      // URDF uses 0 for "not given" in practice; the controller configuration can set limits.
      if (limits->velocity > 0.0) joint.velocity_limit = limits->velocity;
      if (limits->effort > 0.0) joint.effort_limit = limits->effort;
      if (joint.type != JointType::kContinuous) {
        if (limits->lower > limits->upper) {
          fail(where + " <limit>", "lower " + format_general(limits->lower, 6) + " > upper " + format_general(limits->upper, 6));
        }
        if (limits->lower < limits->upper) {
          joint.lower = limits->lower;
          joint.upper = limits->upper;
        }
        if (joint.type == JointType::kRevolute &&
            std::max(std::abs(limits->lower), std::abs(limits->upper)) > kMaxRevoluteLimit_rad + 1e-9) {
          fail(where + " <limit>", "revolute limits [" + format_general(limits->lower, 6) + ", " +
                                       format_general(limits->upper, 6) +
                                       "] rad go beyond one turn each way (|q| <= 2 pi); a joint that turns "
                                       "freely is type 'continuous'");
        }
      }
    } else if (joint.type != JointType::kContinuous) {
      fail(where, "a revolute or prismatic joint needs a <limit>");
    }
    return joint;
  }

  void add_link_inertia(const urdf::Link& link, int body, const Eigen::Isometry3d& placement_in_body) {
    if (!link.inertial) return;
    const std::string where = "link '" + link.name + "' <inertial>";
    if (body < 0) {
      // Fixed to the base: it cannot affect the dynamics, so a bad value there is only reported.
      try {
        (void)checked_inertia(link, where);
      } catch (const ConfigError& e) {
        warn(e.element(), e.reason() + "; ignored: the link is fixed to the base");
      }
      return;
    }
    const std::optional<Inertia> local = checked_inertia(link, where);
    if (!local) return;  // a massless frame link
    const Eigen::Isometry3d inertial_frame = placement_in_body * to_isometry(link.inertial->origin);
    Inertia& target = model_.bodies_[static_cast<std::size_t>(body)];
    target = target.combined_with(local->transformed(inertial_frame));
  }

  // The link's inertial in its inertial frame after the checks; nullopt for a massless link.
  std::optional<Inertia> checked_inertia(const urdf::Link& link, const std::string& where) {
    const urdf::Inertial& in = *link.inertial;
    const double values[] = {in.mass, in.ixx, in.ixy, in.ixz, in.iyy, in.iyz, in.izz};
    for (double v : values) {
      if (!finite(v)) fail(where, "values must be finite (mass or a moment is NaN or infinite)");
    }
    if (!pose_is_finite(in.origin)) fail(where, "origin is not finite");
    Eigen::Matrix3d tensor;
    tensor << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    if (in.mass < 0.0 || (in.mass == 0.0 && !tensor.isZero(0.0))) {
      fail(where, "mass must be positive (got " + format_general(in.mass, 6) + ")");
    }
    if (in.mass > kMaxLinkMass_kg) {
      fail(where, "mass " + format_general(in.mass, 6) + " kg is above 1000 kg: no arm link weighs that");
    }
    if (in.mass == 0.0) {
      if (on_path_.count(link.name) && link.parent_joint && moves(*link.parent_joint)) {
        fail(where, "mass must be positive (got 0) on a link moved by a joint");
      }
      return std::nullopt;
    }
    check_inertia_tensor(tensor, where);
    const double largest_moment = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(tensor, Eigen::EigenvaluesOnly).eigenvalues()[2];
    if (largest_moment > in.mass * kMaxGyrationRadius_m * kMaxGyrationRadius_m) {
      fail(where, "principal moment " + format_general(largest_moment, 6) + " kg.m^2 is too large for the mass " +
                      format_general(in.mass, 6) + " kg (radius of gyration above 2 m)");
    }
    Inertia local;
    local.mass = in.mass;
    local.inertia_com = tensor;
    return local;
  }

  void warn(const std::string& element, const std::string& reason) {
    model_.warnings_.push_back(ConfigError(source_, element, reason).what());
  }

  void check_inertia_tensor(const Eigen::Matrix3d& tensor, const std::string& where) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(tensor, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
    const double scale = std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
    if (ev[0] <= 1e-12 * scale) {
      fail(where, "inertia tensor is not positive definite (principal moments " + format_general(ev[0], 6) + ", " +
                      format_general(ev[1], 6) + ", " + format_general(ev[2], 6) + ")");
    }
    // A rigid body satisfies I1 + I2 >= I3. Manufacturers' files break it (rounded CAD values);
    // Pinocchio, KDL and RBDL accept such a tensor, and the dynamics stay well posed while it is
    // positive definite: a warning, not an error (the plant balances it, see sim/urdf_plant).
    if (ev[0] + ev[1] < ev[2] * (1.0 - 1e-6)) {
      warn(where, "inertia tensor violates the triangle inequality (principal moments " + format_general(ev[0], 6) +
                      " + " + format_general(ev[1], 6) + " < " + format_general(ev[2], 6) +
                      "); accepted as given (positive definite)");
    }
  }

  // A body without mass: either the URDF omits the inertial of the joint's child link while links
  // further down still move (name that link), or nothing at all moves below the joint.
  void check_body(int i) const {
    const Inertia& body = model_.bodies_[static_cast<std::size_t>(i)];
    const Joint& joint = model_.joints_[static_cast<std::size_t>(i)];
    if (body.mass > 0.0) return;
    double mass_below = 0.0;
    for (std::size_t b = static_cast<std::size_t>(i) + 1; b < model_.bodies_.size(); ++b) mass_below += model_.bodies_[b].mass;
    const std::string child = child_link_of(joint.name);
    if (mass_below > 0.0) {
      fail("link '" + child + "'", "has no <inertial> (nor any link fixed to it), yet joint '" + joint.name +
                                       "' moves it: give it its mass (the links below it weigh " +
                                       format_general(mass_below, 4) + " kg, but a moved link needs its own)");
    }
    fail("joint '" + joint.name + "'",
         "moves no mass: its child link '" + child + "' and every link below it have no <inertial>");
  }

  std::string child_link_of(const std::string& joint_name) const {
    const auto joint = urdf_.getJoint(joint_name);
    return joint ? joint->child_link_name : std::string("?");
  }

  void add_extra_frames() {
    for (const ExtraFrame& extra : options_.extra_frames) {
      const std::string where = "ModelOptions.extra_frames '" + extra.name + "'";
      if (extra.name.empty()) fail("ModelOptions.extra_frames", "a frame needs a name");
      if (model_.has_frame(extra.name)) fail(where, "a frame of that name already exists");
      if (!model_.has_frame(extra.parent_frame)) fail(where, "unknown parent frame '" + extra.parent_frame + "'");
      if (!extra.placement.matrix().allFinite()) fail(where, "placement must be finite");
      const Frame& parent = model_.frame(model_.frame_id(extra.parent_frame));
      model_.frames_.push_back(Frame{extra.name, FrameType::kExtra, parent.body, parent.placement * extra.placement});
    }
  }

  void add_payloads() {
    for (const Payload& payload : options_.payloads) {
      const std::string where = "ModelOptions.payloads '" + payload.name + "'";
      if (!model_.has_frame(payload.frame)) fail(where, "unknown frame '" + payload.frame + "'");
      const Inertia& in = payload.inertia;
      if (!(in.mass > 0.0) || !std::isfinite(in.mass)) fail(where, "mass must be positive");
      if (!in.com.allFinite() || !in.inertia_com.allFinite()) fail(where, "values must be finite");
      if ((in.inertia_com - in.inertia_com.transpose()).norm() > 1e-12 * (1.0 + in.inertia_com.norm())) {
        fail(where, "inertia must be symmetric");
      }
      if (!in.inertia_com.isZero(0.0)) check_inertia_tensor(in.inertia_com, where);
      const Frame& frame = model_.frame(model_.frame_id(payload.frame));
      if (frame.body < 0) continue;  // on the base: no effect on the dynamics
      Inertia& body = model_.bodies_[static_cast<std::size_t>(frame.body)];
      body = body.combined_with(in.transformed(frame.placement));
    }
  }

  void apply_armature() {
    if (options_.armature.empty()) return;
    if (static_cast<int>(options_.armature.size()) != model_.nq()) {
      fail("ModelOptions.armature", "has " + std::to_string(options_.armature.size()) + " values for " +
                                        std::to_string(model_.nq()) + " joints");
    }
    for (int i = 0; i < model_.nq(); ++i) {
      const double a = options_.armature[static_cast<std::size_t>(i)];
      if (!finite(a) || a < 0.0) fail("ModelOptions.armature", "values must be finite and >= 0");
      model_.joints_[static_cast<std::size_t>(i)].armature = a;
    }
  }

  const urdf::ModelInterface& urdf_;
  const ModelOptions& options_;
  std::string source_;
  Model model_;
  std::map<std::string, bool> on_path_;
};

// ---------------------------------------------------------------------------------- Model
namespace {
// "Could not parse inertial element for Link [hand]": the link urdfdom names, for the key path.
std::string link_named_in(const std::string& message) {
  const std::string marker = "Link [";
  const auto begin = message.find(marker);
  if (begin == std::string::npos) return "";
  const auto end = message.find(']', begin + marker.size());
  if (end == std::string::npos) return "";
  const std::string link = "link '" + message.substr(begin + marker.size(), end - begin - marker.size()) + "'";
  return message.find("inertial") != std::string::npos ? link + " <inertial>" : link;
}
}  // namespace

Model Model::from_urdf_string(const std::string& urdf, const ModelOptions& options,
                              const std::string& source_name) {
  urdf::ModelInterfaceSharedPtr parsed;
  CapturingOutput capture;
  {
    std::lock_guard<std::mutex> lock(urdf_parser_mutex());
    console_bridge::useOutputHandler(&capture);
    try {
      parsed = urdf::parseURDF(urdf);
    } catch (const std::exception& e) {
      capture.errors += e.what();
      parsed.reset();
    }
    console_bridge::restorePreviousOutputHandler();
  }
  if (!parsed) {
    throw ConfigError(source_name, "", "not a valid URDF" + (capture.errors.empty() ? std::string() : " (" + capture.errors + ")"));
  }
  if (!capture.errors.empty()) {
    // urdfdom went on after an error, dropping what it could not parse (e.g. a link's mass).
    throw ConfigError(source_name, link_named_in(capture.errors),
                      "urdfdom could not parse it and would drop the value (" + capture.errors + ")");
  }
  check_origins(urdf, source_name);
  return UrdfModelBuilder(*parsed, options, source_name, std::move(capture.warnings)).build();
}

Model Model::from_urdf_file(const std::string& path, const ModelOptions& options) {
  std::ifstream file(path);
  if (!file) throw ConfigError(path, "", "cannot open the file");
  std::stringstream contents;
  contents << file.rdbuf();
  return from_urdf_string(contents.str(), options, path);
}

int Model::frame_id(const std::string& name) const {
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    if (frames_[f].name == name) return static_cast<int>(f);
  }
  throw ConfigError(name_, "frame '" + name + "'", "no such frame in the model");
}

bool Model::has_frame(const std::string& name) const {
  return std::any_of(frames_.begin(), frames_.end(), [&](const Frame& f) { return f.name == name; });
}

int Model::joint_id(const std::string& name) const {
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    if (joints_[j].name == name) return static_cast<int>(j);
  }
  throw ConfigError(name_, "joint '" + name + "'", "no such joint in the chain");
}

namespace {
template <typename Getter>
Eigen::VectorXd collect(const std::vector<Joint>& joints, Getter get) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(joints.size()));
  for (std::size_t i = 0; i < joints.size(); ++i) out[static_cast<Eigen::Index>(i)] = get(joints[i]);
  return out;
}
}  // namespace

Eigen::VectorXd Model::lower_limits() const { return collect(joints_, [](const Joint& j) { return j.lower; }); }
Eigen::VectorXd Model::upper_limits() const { return collect(joints_, [](const Joint& j) { return j.upper; }); }
Eigen::VectorXd Model::velocity_limits() const { return collect(joints_, [](const Joint& j) { return j.velocity_limit; }); }
Eigen::VectorXd Model::effort_limits() const { return collect(joints_, [](const Joint& j) { return j.effort_limit; }); }

double Model::total_mass() const {
  double m = 0.0;
  for (const Inertia& b : bodies_) m += b.mass;
  return m;
}

}  // namespace phri
