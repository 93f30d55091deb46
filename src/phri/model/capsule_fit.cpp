#include <phri/model/capsule_fit.hpp>

#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/core/parser_lock.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/collision_model.hpp>

#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>
#include <sstream>

namespace phri {
namespace {

struct FittedCapsule {
  std::string link;
  int body = -1;
  Eigen::Vector3d p0, p1;  // link frame
  double radius = 0.0;
};

Eigen::Isometry3d to_isometry(const urdf::Pose& pose) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z).normalized().toRotationMatrix();
  out.translation() << pose.position.x, pose.position.y, pose.position.z;
  return out;
}

// A geometry as pieces whose convex hull it is: a box's corners (radius 0), a sphere (a ball), a
// cylinder's two end discs (normal: its axis). In the link frame.
struct Piece {
  Eigen::Vector3d centre;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // a disc's; zero for a corner or a ball
  double radius = 0.0;
};

// False for a mesh (not read here).
bool add_pieces(const urdf::Collision& collision, std::vector<Piece>& pieces) {
  if (!collision.geometry) return false;
  const Eigen::Isometry3d origin = to_isometry(collision.origin);
  const urdf::Geometry& g = *collision.geometry;
  if (g.type == urdf::Geometry::BOX) {
    const auto& box = static_cast<const urdf::Box&>(g);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d sign((corner & 1) ? 1.0 : -1.0, (corner & 2) ? 1.0 : -1.0, (corner & 4) ? 1.0 : -1.0);
      pieces.push_back({origin * (0.5 * sign.cwiseProduct(Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z)))});
    }
    return true;
  }
  if (g.type == urdf::Geometry::CYLINDER) {
    const auto& cylinder = static_cast<const urdf::Cylinder&>(g);
    const Eigen::Vector3d axis = origin.linear().col(2);
    for (double z : {-0.5 * cylinder.length, 0.5 * cylinder.length}) {
      pieces.push_back({origin * Eigen::Vector3d(0.0, 0.0, z), axis, cylinder.radius});
    }
    return true;
  }
  if (g.type == urdf::Geometry::SPHERE) {
    pieces.push_back({origin.translation(), Eigen::Vector3d::Zero(), static_cast<const urdf::Sphere&>(g).radius});
    return true;
  }
  return false;
}

// Sample points of the pieces (centres, and extreme points of balls and discs), for the axis.
std::vector<Eigen::Vector3d> samples_of(const std::vector<Piece>& pieces) {
  std::vector<Eigen::Vector3d> samples;
  for (const Piece& p : pieces) {
    samples.push_back(p.centre);
    for (int axis = 0; axis < 3 && p.radius > 0.0; ++axis) {
      const Eigen::Vector3d d = Eigen::Vector3d::Unit(axis) - p.normal * p.normal.dot(Eigen::Vector3d::Unit(axis));
      if (d.norm() < 1e-9) continue;
      samples.push_back(p.centre + p.radius * d.normalized());
      samples.push_back(p.centre - p.radius * d.normalized());
    }
  }
  return samples;
}

// The axis: the samples' principal direction. The segment spans every piece's extent along it and
// the radius bounds every piece's distance from it (for a disc centred on the axis and square to
// it, exactly its radius): the capsule encloses the pieces' convex hull.
void fit_to_pieces(const std::vector<Piece>& pieces, FittedCapsule& capsule) {
  const std::vector<Eigen::Vector3d> samples = samples_of(pieces);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& x : samples) centre += x;
  centre /= static_cast<double>(samples.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& x : samples) scatter += (x - centre) * (x - centre).transpose();
  const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(2);
  double low = 0.0, high = 0.0, radius = 0.0;
  for (const Piece& p : pieces) {
    const double t = axis.dot(p.centre - centre);
    // Along the axis a ball reaches r, a disc r sqrt(1 - (axis . normal)^2).
    const double square = axis.dot(p.normal);
    const double reach = p.normal.isZero() ? p.radius : p.radius * std::sqrt(std::max(0.0, 1.0 - square * square));
    low = std::min(low, t - reach);
    high = std::max(high, t + reach);
    radius = std::max(radius, (p.centre - centre - t * axis).norm() + p.radius);
  }
  capsule.p0 = centre + low * axis;
  capsule.p1 = centre + high * axis;
  capsule.radius = radius;
}

double offset(const urdf::Joint& joint) {
  const urdf::Vector3& p = joint.parent_to_joint_origin_transform.position;
  return std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
}

// The child joint of `link` toward the model's tip link, else its farthest child joint: where the
// link's capsule ends. Null when the link has no child joint away from its origin.
const urdf::Joint* next_joint(const urdf::ModelInterface& urdf, const urdf::Link& link, const Model& model) {
  const auto tip = urdf.getLink(model.tip_link());
  for (const urdf::Link* up = tip.get(); up != nullptr && up->getParent(); up = up->getParent().get()) {
    if (up->getParent().get() == &link && offset(*up->parent_joint) > 1e-9) return up->parent_joint.get();
  }
  const urdf::Joint* farthest = nullptr;
  for (const auto& joint : link.child_joints) {
    if (offset(*joint) > 1e-9 && (farthest == nullptr || offset(*joint) > offset(*farthest))) farthest = joint.get();
  }
  return farthest;
}

bool is_body_link(const urdf::Link& link, const Model& model) {
  if (!model.has_frame(link.name)) return false;
  if (link.name == model.base_link()) return true;
  return link.parent_joint && link.parent_joint->type != urdf::Joint::FIXED && model.frame(model.frame_id(link.name)).body >= 0 &&
         model.frame(model.frame_id(link.name)).placement.isApprox(Eigen::Isometry3d::Identity());
}

std::vector<FittedCapsule> fit_links(const urdf::ModelInterface& urdf, const Model& model, const CapsuleFitOptions& options,
                                     std::vector<std::string>& notes) {
  std::vector<FittedCapsule> out;
  for (const Frame& frame : model.frames()) {
    const auto link = frame.type == FrameType::kLink ? urdf.getLink(frame.name) : nullptr;
    if (!link) continue;
    FittedCapsule capsule{frame.name, frame.body, {}, {}, 0.0};
    std::vector<Piece> pieces;
    bool mesh = false;
    for (const auto& collision : link->collision_array) mesh |= !add_pieces(*collision, pieces);
    if (!pieces.empty()) {
      fit_to_pieces(pieces, capsule);
    } else if (is_body_link(*link, model)) {
      const urdf::Joint* next = next_joint(urdf, *link, model);
      capsule.p0 = Eigen::Vector3d::Zero();
      capsule.radius = options.link_frame_radius_m;
      if (next != nullptr) {
        const urdf::Vector3& p = next->parent_to_joint_origin_transform.position;
        capsule.p1 = Eigen::Vector3d(p.x, p.y, p.z);
      } else if (link->inertial && link->inertial->mass > 0.0) {
        // Its child joints (if any) sit at its origin, as in a wrist whose axes meet: the link's
        // body still has mass around its centre of mass. A segment from the origin through the
        // COM to twice as far (the COM in its middle; a sphere at the origin when they coincide).
        const urdf::Vector3& c = link->inertial->origin.position;
        capsule.p1 = 2.0 * Eigen::Vector3d(c.x, c.y, c.z);
        notes.push_back("link '" + frame.name + "': no collision geometry and " +
                        (link->child_joints.empty() ? std::string("no child joint") : "its child joints at its origin") +
                        ": a capsule through its centre of mass");
      } else {
        notes.push_back("link '" + frame.name + "': no collision geometry, " +
                        (link->child_joints.empty() ? std::string("no child joint") : "its child joints at its origin") +
                        " and no mass: no capsule");
        continue;
      }
    } else {
      continue;  // a frame merged into its parent's body, without geometry of its own
    }
    if (mesh) notes.push_back("link '" + frame.name + "': a mesh cannot be read here; fitted to its other geometry or frames");
    out.push_back(capsule);
  }
  return out;
}

std::string number(double v) { return format_general(std::abs(v) < 1e-12 ? 0.0 : v, 12); }

std::string point(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s << '[' << number(p.x()) << ", " << number(p.y()) << ", " << number(p.z()) << ']';
  return s.str();
}

std::string capsules_yaml(const std::vector<FittedCapsule>& capsules) {
  std::ostringstream yaml;
  yaml << "capsules:\n";
  for (const FittedCapsule& c : capsules) {
    yaml << "  - {link: " << c.link << ", p0: " << point(c.p0) << ", p1: " << point(c.p1) << ", radius: " << number(c.radius)
         << "}\n";
  }
  return yaml.str();
}

std::string pairs_yaml(const std::vector<std::pair<std::string, std::string>>& pairs) {
  if (pairs.empty()) return "pairs: []\n";
  std::ostringstream yaml;
  yaml << "pairs:\n";
  for (const auto& [a, b] : pairs) yaml << "  - [" << a << ", " << b << "]\n";
  return yaml.str();
}

}  // namespace

CapsuleFit fit_capsules(const std::string& urdf, const Model& model, const Eigen::VectorXd& home_q,
                        const CapsuleFitOptions& options) {
  if (home_q.size() != model.nq()) {
    throw ConfigError(model.name(), "home_q", "has " + std::to_string(home_q.size()) + " values for " +
                                                  std::to_string(model.nq()) + " joints");
  }
  urdf::ModelInterfaceSharedPtr parsed;
  {
    // The model of the same text loaded already: nothing to capture; the lock keeps the parser's
    // messages out of another thread's capture.
    std::lock_guard<std::mutex> lock(urdf_parser_mutex());
    parsed = urdf::parseURDF(urdf);
  }
  if (!parsed) throw ConfigError(model.name(), "", "not a valid URDF");
  CapsuleFit fit;
  const std::vector<FittedCapsule> capsules = fit_links(*parsed, model, options, fit.notes);
  std::vector<std::pair<std::string, std::string>> candidates;
  for (std::size_t a = 0; a < capsules.size(); ++a) {
    for (std::size_t b = a + 1; b < capsules.size(); ++b) {
      if (std::abs(capsules[a].body - capsules[b].body) > 1) candidates.emplace_back(capsules[a].link, capsules[b].link);
    }
  }
  // Distances at the home posture, through the loader the controller uses.
  const CollisionModel all = CollisionModel::from_yaml_string(capsules_yaml(capsules) + pairs_yaml(candidates), model, "fitted capsules");
  Data data(model);
  forward_kinematics(model, data, home_q);
  CollisionData distances(model, all);
  compute_collision_distances(model, data, all, distances, false);
  std::vector<std::pair<std::string, std::string>> pairs;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const double d = distances.distance[static_cast<Eigen::Index>(k)];
    if (d < options.clearance_m) {
      std::ostringstream note;
      note << "pair [" << candidates[k].first << ", " << candidates[k].second << "] left out: " << format_general(d, 4)
           << " m apart at the home posture";
      fit.notes.push_back(note.str());
      continue;
    }
    pairs.push_back(candidates[k]);
  }
  fit.yaml = "# Fitted by phri::fit_capsules from the URDF (src/phri/model/capsule_fit.hpp): p0, p1 in the link frame [m].\n" +
             capsules_yaml(capsules) + pairs_yaml(pairs);
  fit.capsules = static_cast<int>(capsules.size());
  fit.pairs = static_cast<int>(pairs.size());
  return fit;
}

}  // namespace phri
