#include <phri/model/collision_model.hpp>

#include <phri/core/config_error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/capsule_distance.hpp>

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace phri {

// ---------------------------------------------------------------------------------- loading
namespace {

class CollisionYamlReader {
public:
  CollisionYamlReader(const Model& model, std::string source) : model_(model), source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    throw ConfigError(source_, key, reason);
  }

  void only_keys(const YAML::Node& node, const std::string& path, const std::set<std::string>& allowed) const {
    for (const auto& item : node) {
      const std::string key = item.first.as<std::string>();
      if (!allowed.count(key)) fail(path.empty() ? key : path + "." + key, "unknown key");
    }
  }

  double number(const YAML::Node& node, const std::string& path) const {
    if (!node || !node.IsScalar()) fail(path, "expected a number");
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      fail(path, "expected a number, got '" + node.Scalar() + "'");
    }
    if (!std::isfinite(value)) fail(path, "must be finite");
    return value;
  }

  Eigen::Vector3d vector3(const YAML::Node& node, const std::string& path) const {
    if (!node || !node.IsSequence() || node.size() != 3) fail(path, "expected a list of 3 numbers");
    return {number(node[0], path + "[0]"), number(node[1], path + "[1]"), number(node[2], path + "[2]")};
  }

  std::string link_name(const YAML::Node& node, const std::string& path) const {
    if (!node || !node.IsScalar()) fail(path, "expected a link name");
    const std::string name = node.as<std::string>();
    if (!model_.has_frame(name)) fail(path, "unknown link '" + name + "'");
    return name;
  }

  void read(const YAML::Node& root, std::vector<Capsule>& capsules, std::vector<CapsulePair>& pairs) const {
    if (!root || !root.IsMap()) fail("", "expected a map with 'capsules' and 'pairs'");
    only_keys(root, "", {"capsules", "pairs"});
    const YAML::Node list = root["capsules"];
    if (!list || !list.IsSequence()) fail("capsules", "expected a list of capsules");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string path = "capsules[" + std::to_string(i) + "]";
      const YAML::Node item = list[i];
      if (!item.IsMap()) fail(path, "expected {link, p0, p1, radius}");
      only_keys(item, path, {"link", "p0", "p1", "radius"});
      Capsule capsule;
      capsule.link = link_name(item["link"], path + ".link");
      const Frame& frame = model_.frame(model_.frame_id(capsule.link));
      capsule.body = frame.body;
      capsule.p0 = frame.placement * vector3(item["p0"], path + ".p0");
      capsule.p1 = frame.placement * vector3(item["p1"], path + ".p1");
      capsule.radius = number(item["radius"], path + ".radius");
      if (capsule.radius <= 0.0) fail(path + ".radius", "must be positive");
      for (const Capsule& other : capsules) {
        if (other.link == capsule.link) fail(path + ".link", "a second capsule for '" + capsule.link + "'");
      }
      capsules.push_back(capsule);
    }
    auto capsule_index = [&](const std::string& link, const std::string& path) {
      for (std::size_t c = 0; c < capsules.size(); ++c) {
        if (capsules[c].link == link) return static_cast<int>(c);
      }
      fail(path, "link '" + link + "' has no capsule");
    };
    const YAML::Node pair_list = root["pairs"];
    if (!pair_list || !pair_list.IsSequence()) fail("pairs", "expected a list of [link_a, link_b]");
    for (std::size_t i = 0; i < pair_list.size(); ++i) {
      const std::string path = "pairs[" + std::to_string(i) + "]";
      const YAML::Node item = pair_list[i];
      if (!item.IsSequence() || item.size() != 2) fail(path, "expected [link_a, link_b]");
      CapsulePair pair;
      pair.first = capsule_index(link_name(item[0], path + "[0]"), path + "[0]");
      pair.second = capsule_index(link_name(item[1], path + "[1]"), path + "[1]");
      const Capsule& a = capsules[static_cast<std::size_t>(pair.first)];
      const Capsule& b = capsules[static_cast<std::size_t>(pair.second)];
      if (a.body == b.body) fail(path, "both capsules move with the same body: their distance never changes");
      pairs.push_back(pair);
    }
  }

private:
  const Model& model_;
  std::string source_;
};

}  // namespace

CollisionModel CollisionModel::from_yaml_string(const std::string& yaml, const Model& model,
                                                const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name, "line " + std::to_string(e.mark.line + 1), std::string("not valid YAML: ") + e.msg);
  }
  CollisionModel out;
  CollisionYamlReader(model, source_name).read(root, out.capsules_, out.pairs_);
  return out;
}

CollisionModel CollisionModel::from_yaml_file(const std::string& path, const Model& model) {
  std::ifstream file(path);
  if (!file) throw ConfigError(path, "", "cannot open the file");
  std::stringstream contents;
  contents << file.rdbuf();
  return from_yaml_string(contents.str(), model, path);
}

// ---------------------------------------------------------------------------------- distances
CollisionData::CollisionData(const Model& model, const CollisionModel& collision)
    : distance(Eigen::VectorXd::Zero(collision.num_pairs())),
      point_first(Eigen::Matrix3Xd::Zero(3, collision.num_pairs())),
      point_second(Eigen::Matrix3Xd::Zero(3, collision.num_pairs())),
      normal(Eigen::Matrix3Xd::Zero(3, collision.num_pairs())),
      jacobian(Eigen::MatrixXd::Zero(collision.num_pairs(), model.nv())),
      jdot_qdot(Eigen::VectorXd::Zero(collision.num_pairs())),
      velocity(Eigen::VectorXd::Zero(collision.num_pairs())),
      scratch_first(Eigen::MatrixXd::Zero(3, model.nv())),
      scratch_second(Eigen::MatrixXd::Zero(3, model.nv())) {}

namespace {
const Eigen::Isometry3d& placement_of(const Model& model, const Data& data, int body) {
  return body < 0 ? model.base_placement() : data.body_placements[static_cast<std::size_t>(body)];
}
}  // namespace

void compute_collision_distances(const Model& model, const Data& data, const CollisionModel& collision,
                                 CollisionData& out, bool with_derivatives) {
  for (int k = 0; k < collision.num_pairs(); ++k) {
    const CapsulePair& pair = collision.pairs()[static_cast<std::size_t>(k)];
    const Capsule& a = collision.capsules()[static_cast<std::size_t>(pair.first)];
    const Capsule& b = collision.capsules()[static_cast<std::size_t>(pair.second)];
    const Eigen::Isometry3d& pa = placement_of(model, data, a.body);
    const Eigen::Isometry3d& pb = placement_of(model, data, b.body);
    const Eigen::Vector3d a0 = pa * a.p0, a1 = pa * a.p1, b0 = pb * b.p0, b1 = pb * b.p1;
    const SegmentClosestPoints closest = closest_points_between_segments(a0, a1, b0, b1);
    const Eigen::Vector3d gap = closest.on_first - closest.on_second;
    const double axis_distance = gap.norm();
    Eigen::Vector3d n;
    if (axis_distance > 1e-9) {
      n = gap / axis_distance;
    } else {
      // Axes intersect (deep penetration): any direction normal to both axes separates them.
      n = (a1 - a0).cross(b1 - b0);
      if (n.norm() < 1e-12) n = (a1 - a0).unitOrthogonal();
      n.normalize();
    }
    out.distance[k] = axis_distance - a.radius - b.radius;
    out.point_first.col(k) = closest.on_first;
    out.point_second.col(k) = closest.on_second;
    out.normal.col(k) = n;
    if (!with_derivatives) continue;
    // d = n.(p_a - p_b) changes at n.(v_a - v_b), with v the velocities of the body-fixed points
    // now at the closest points (envelope theorem): that gives the distance Jacobian.
    body_point_linear_jacobian(model, data, a.body, closest.on_first, out.scratch_first);
    body_point_linear_jacobian(model, data, b.body, closest.on_second, out.scratch_second);
    out.jacobian.row(k).noalias() = n.transpose() * (out.scratch_first - out.scratch_second);
    const Eigen::Vector3d relative_velocity = body_point_velocity(model, data, a.body, closest.on_first) -
                                              body_point_velocity(model, data, b.body, closest.on_second);
    out.velocity[k] = n.dot(relative_velocity);
    // Second derivative: the closest points also slide along the axes (s', t'), found by
    // differentiating the optimality conditions gap.u_a = 0 (s free) and gap.u_b = 0 (t free).
    const Eigen::Vector3d u_a = a1 - a0, u_b = b1 - b0;
    const Eigen::Vector3d w_a = a.body < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(data.body_velocities.col(a.body).tail<3>());
    const Eigen::Vector3d w_b = b.body < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(data.body_velocities.col(b.body).tail<3>());
    const bool s_free = closest.s > 0.0 && closest.s < 1.0 && u_a.squaredNorm() > 1e-18;
    const bool t_free = closest.t > 0.0 && closest.t < 1.0 && u_b.squaredNorm() > 1e-18;
    const double r_a = -relative_velocity.dot(u_a) - gap.dot(w_a.cross(u_a));
    const double r_b = -relative_velocity.dot(u_b) - gap.dot(w_b.cross(u_b));
    double s_rate = 0.0, t_rate = 0.0;
    if (s_free && t_free) {
      const double uaua = u_a.squaredNorm(), uaub = u_a.dot(u_b), ubub = u_b.squaredNorm();
      const double det = uaub * uaub - uaua * ubub;  // zero for parallel axes: closest points not unique
      if (std::abs(det) > 1e-9 * uaua * ubub) {
        s_rate = (-ubub * r_a + uaub * r_b) / det;
        t_rate = (-uaub * r_a + uaua * r_b) / det;
      }
    } else if (s_free) {
      s_rate = r_a / u_a.squaredNorm();
    } else if (t_free) {
      t_rate = -r_b / u_b.squaredNorm();
    }
    const Eigen::Vector3d relative_bias = body_point_jdot_qdot(model, data, a.body, closest.on_first) -
                                          body_point_jdot_qdot(model, data, b.body, closest.on_second) +
                                          w_a.cross(s_rate * u_a) - w_b.cross(t_rate * u_b);
    const Eigen::Vector3d gap_rate = relative_velocity + s_rate * u_a - t_rate * u_b;
    const Eigen::Vector3d tangential = gap_rate - n * n.dot(gap_rate);  // rotation of n
    out.jdot_qdot[k] = n.dot(relative_bias) +
                       (axis_distance > 1e-9 ? tangential.dot(relative_velocity) / axis_distance : 0.0);
  }
}

}  // namespace phri
