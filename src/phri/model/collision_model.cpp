#include <phri/model/collision_model.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/capsule_distance.hpp>

#include <phri/core/yaml_reader.hpp>

#include <cmath>

namespace phri {

// ---------------------------------------------------------------------------------- loading
namespace {

// A capsule's radius at most 0.5 m (an arm link is ~0.1 m across: the Gen3's capsules are 0.035 to
// 0.045 m) and its end points within 2 m of its link frame (every link lies within the arm's reach).
constexpr double kMaxCapsuleRadius_m = 0.5;
constexpr double kMaxCapsuleExtent_m = 2.0;

// The pair's bodies are connected by one joint (or are the base and the first body): their
// capsules meet at that joint by construction, so the pair would always read "in collision".
bool adjacent(int body_a, int body_b) { return std::abs(body_a - body_b) == 1; }

void read_collision_yaml(const YamlReader& root, const Model& model, std::vector<Capsule>& capsules,
                         std::vector<CapsulePair>& pairs) {
  root.expect_map();
  root.allow_keys({"capsules", "pairs"});
  auto link_of = [&](const YamlReader& node) {
    const std::string name = node.as_text();
    if (!model.has_frame(name)) throw node.error("", "unknown link '" + name + "'");
    return name;
  };
  const YamlReader list = root.at("capsules");
  list.expect_sequence();
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YamlReader item = list.at(i);
    item.expect_map();
    item.allow_keys({"link", "p0", "p1", "radius"});
    Capsule capsule;
    capsule.link = link_of(item.at("link"));
    const Frame& frame = model.frame(model.frame_id(capsule.link));
    capsule.body = frame.body;
    const auto p0 = item.numbers("p0", 3, -kMaxCapsuleExtent_m, kMaxCapsuleExtent_m);
    const auto p1 = item.numbers("p1", 3, -kMaxCapsuleExtent_m, kMaxCapsuleExtent_m);
    capsule.p0 = frame.placement * Eigen::Vector3d(p0[0], p0[1], p0[2]);
    capsule.p1 = frame.placement * Eigen::Vector3d(p1[0], p1[1], p1[2]);
    capsule.radius = item.number("radius", 1e-6, kMaxCapsuleRadius_m);
    for (const Capsule& other : capsules) {
      if (other.link == capsule.link) throw item.error("link", "a second capsule for '" + capsule.link + "'");
    }
    capsules.push_back(capsule);
  }
  auto capsule_index = [&](const YamlReader& node) {
    const std::string link = link_of(node);
    for (std::size_t c = 0; c < capsules.size(); ++c) {
      if (capsules[c].link == link) return static_cast<int>(c);
    }
    throw node.error("", "link '" + link + "' has no capsule");
  };
  const YamlReader pair_list = root.at("pairs");
  pair_list.expect_sequence();
  for (std::size_t i = 0; i < pair_list.size(); ++i) {
    const YamlReader item = pair_list.at(i);
    item.expect_sequence();
    if (item.size() != 2) throw item.error("", "expected [link_a, link_b]");
    CapsulePair pair;
    pair.first = capsule_index(item.at(std::size_t{0}));
    pair.second = capsule_index(item.at(std::size_t{1}));
    const int body_a = capsules[static_cast<std::size_t>(pair.first)].body;
    const int body_b = capsules[static_cast<std::size_t>(pair.second)].body;
    if (body_a == body_b) throw item.error("", "both capsules move with the same body: their distance never changes");
    if (adjacent(body_a, body_b)) {
      const std::string joint = model.joint(std::max(body_a, body_b)).name;
      throw item.error("", "links connected by one joint ('" + joint +
                               "'): their capsules meet at the joint, the pair would always be in collision");
    }
    pairs.push_back(pair);
  }
}

}  // namespace

CollisionModel CollisionModel::from_yaml_string(const std::string& yaml, const Model& model,
                                                const std::string& source_name) {
  CollisionModel out;
  read_collision_yaml(YamlReader::load_string(yaml, source_name), model, out.capsules_, out.pairs_);
  return out;
}

CollisionModel CollisionModel::from_yaml_file(const std::string& path, const Model& model) {
  CollisionModel out;
  read_collision_yaml(YamlReader::load_file(path), model, out.capsules_, out.pairs_);
  return out;
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
      s(Eigen::VectorXd::Zero(collision.num_pairs())),
      t(Eigen::VectorXd::Zero(collision.num_pairs())),
      scratch_first(Eigen::MatrixXd::Zero(3, model.nv())),
      scratch_second(Eigen::MatrixXd::Zero(3, model.nv())),
      capsule_center(Eigen::Matrix3Xd::Zero(3, static_cast<Eigen::Index>(collision.capsules().size()))),
      capsule_speed(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(collision.capsules().size()))),
      capsule_angular_speed(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(collision.capsules().size()))),
      distance_lower_bound(Eigen::VectorXd::Zero(collision.num_pairs())),
      approach_speed_bound(Eigen::VectorXd::Zero(collision.num_pairs())),
      capsule_midpoint(3, static_cast<Eigen::Index>(collision.capsules().size())),
      capsule_half_length(static_cast<Eigen::Index>(collision.capsules().size())),
      pair_reach(collision.num_pairs()) {
  const std::vector<Capsule>& capsules = collision.capsules();
  for (std::size_t c = 0; c < capsules.size(); ++c) {
    const auto i = static_cast<Eigen::Index>(c);
    capsule_midpoint.col(i) = 0.5 * (capsules[c].p0 + capsules[c].p1);
    capsule_half_length[i] = 0.5 * (capsules[c].p1 - capsules[c].p0).norm();
  }
  for (int k = 0; k < collision.num_pairs(); ++k) {
    const CapsulePair& pair = collision.pairs()[static_cast<std::size_t>(k)];
    pair_reach[k] = capsule_half_length[pair.first] + capsules[static_cast<std::size_t>(pair.first)].radius +
                    capsule_half_length[pair.second] + capsules[static_cast<std::size_t>(pair.second)].radius;
  }
}

namespace {
const Eigen::Isometry3d& placement_of(const Model& model, const Data& data, int body) {
  return body < 0 ? model.base_placement() : data.body_placements[static_cast<std::size_t>(body)];
}

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

// Pair k's two capsules and the end points of their axes in the world.
struct PairAxes {
  const Capsule& a;
  const Capsule& b;
  Eigen::Vector3d a0, a1, b0, b1;
};
PairAxes pair_axes(const Model& model, const Data& data, const CollisionModel& collision, int k) {
  const CapsulePair& pair = collision.pairs()[static_cast<std::size_t>(k)];
  const Capsule& a = collision.capsules()[static_cast<std::size_t>(pair.first)];
  const Capsule& b = collision.capsules()[static_cast<std::size_t>(pair.second)];
  const Eigen::Isometry3d& pa = placement_of(model, data, a.body);
  const Eigen::Isometry3d& pb = placement_of(model, data, b.body);
  return {a, b, pa * a.p0, pa * a.p1, pb * b.p0, pb * b.p1};
}

// Distance, closest points and normal of pair k; with_rate: its velocity too.
void pair_distance(const Model& model, const Data& data, const CollisionModel& collision, int k, bool with_rate,
                   CollisionData& out) {
  const auto [a, b, a0, a1, b0, b1] = pair_axes(model, data, collision, k);
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
  out.s[k] = closest.s;
  out.t[k] = closest.t;
  if (!with_rate) return;
  // d = n.(p_a - p_b) changes at n.(v_a - v_b), with v the velocities of the body-fixed points
  // now at the closest points (envelope theorem).
  out.velocity[k] = n.dot(body_point_velocity(model, data, a.body, closest.on_first) -
                          body_point_velocity(model, data, b.body, closest.on_second));
}
}  // namespace

void compute_collision_distance_rates(const Model& model, const Data& data, const CollisionModel& collision,
                                      CollisionData& out) {
  for (int k = 0; k < collision.num_pairs(); ++k) pair_distance(model, data, collision, k, true, out);
}

void compute_collision_pair_distance_rate(const Model& model, const Data& data, const CollisionModel& collision, int k,
                                          CollisionData& out) {
  pair_distance(model, data, collision, k, true, out);
}

void compute_collision_bounds(const Model& model, const Data& data, const CollisionModel& collision, CollisionData& out) {
  // Squared norms first, then their square roots in vectorised batches (one at a time, the
  // square roots' latency was most of the pass); each the same rounding as the norm.
  const std::vector<Capsule>& capsules = collision.capsules();
  for (std::size_t c = 0; c < capsules.size(); ++c) {
    const int body = capsules[c].body;
    const auto i = static_cast<Eigen::Index>(c);
    const Eigen::Vector3d center = placement_of(model, data, body) * out.capsule_midpoint.col(i);
    out.capsule_center.col(i) = center;
    if (body < 0) {
      out.capsule_speed[i] = out.capsule_angular_speed[i] = 0.0;
      continue;
    }
    out.capsule_angular_speed[i] = data.body_velocities.col(body).tail<3>().squaredNorm();
    out.capsule_speed[i] = body_point_velocity(model, data, body, center).squaredNorm();
  }
  out.capsule_speed =
      out.capsule_speed.array().sqrt() + out.capsule_angular_speed.array().sqrt() * out.capsule_half_length.array();
  for (int k = 0; k < collision.num_pairs(); ++k) {
    const CapsulePair& pair = collision.pairs()[static_cast<std::size_t>(k)];
    out.distance_lower_bound[k] = (out.capsule_center.col(pair.first) - out.capsule_center.col(pair.second)).squaredNorm();
    out.approach_speed_bound[k] = out.capsule_speed[pair.first] + out.capsule_speed[pair.second];
  }
  out.distance_lower_bound = out.distance_lower_bound.array().sqrt() - out.pair_reach.array();
}

void compute_collision_distances(const Model& model, const Data& data, const CollisionModel& collision,
                                 CollisionData& out, bool with_derivatives) {
  for (int k = 0; k < collision.num_pairs(); ++k) {
    pair_distance(model, data, collision, k, with_derivatives, out);
    if (with_derivatives) compute_collision_pair_derivatives(model, data, collision, k, out);
  }
}

void compute_collision_pair_derivatives(const Model& model, const Data& data, const CollisionModel& collision, int k,
                                        CollisionData& out) {
  const auto [a, b, a0, a1, b0, b1] = pair_axes(model, data, collision, k);
  const Eigen::Vector3d on_first = out.point_first.col(k), on_second = out.point_second.col(k);
  const Eigen::Vector3d n = out.normal.col(k);
  const Eigen::Vector3d gap = on_first - on_second;
  const double axis_distance = gap.norm();
  // The distance Jacobian: n^T (J_a - J_b) at the closest points.
  body_point_linear_jacobian(model, data, a.body, on_first, out.scratch_first);
  body_point_linear_jacobian(model, data, b.body, on_second, out.scratch_second);
  out.jacobian.row(k).noalias() = n.transpose() * (out.scratch_first - out.scratch_second);
  const Eigen::Vector3d relative_velocity =
      body_point_velocity(model, data, a.body, on_first) - body_point_velocity(model, data, b.body, on_second);
  // Second derivative: the closest points also slide along the axes (s', t'), found by
  // differentiating the optimality conditions gap.u_a = 0 (s free) and gap.u_b = 0 (t free).
  const Eigen::Vector3d u_a = a1 - a0, u_b = b1 - b0;
  const Eigen::Vector3d w_a = a.body < 0 ? kZero : Eigen::Vector3d(data.body_velocities.col(a.body).tail<3>());
  const Eigen::Vector3d w_b = b.body < 0 ? kZero : Eigen::Vector3d(data.body_velocities.col(b.body).tail<3>());
  const bool s_free = out.s[k] > 0.0 && out.s[k] < 1.0 && u_a.squaredNorm() > 1e-18;
  const bool t_free = out.t[k] > 0.0 && out.t[k] < 1.0 && u_b.squaredNorm() > 1e-18;
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
  const Eigen::Vector3d relative_bias = body_point_jdot_qdot(model, data, a.body, on_first) -
                                        body_point_jdot_qdot(model, data, b.body, on_second) +
                                        w_a.cross(s_rate * u_a) - w_b.cross(t_rate * u_b);
  const Eigen::Vector3d gap_rate = relative_velocity + s_rate * u_a - t_rate * u_b;
  const Eigen::Vector3d tangential = gap_rate - n * n.dot(gap_rate);  // rotation of n
  out.jdot_qdot[k] = n.dot(relative_bias) + (axis_distance > 1e-9 ? tangential.dot(relative_velocity) / axis_distance : 0.0);
}

}  // namespace phri
