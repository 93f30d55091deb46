#include <phri/experiments/safety_fuzz_cases.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace phri {

std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a + 0x9E3779B97F4A7C15ULL * (b + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

ExternalForce PushSpec::disturbance(double start_s) const {
  ExternalForce f;
  f.point_m = plant_body.empty() ? point_local : plant_point_local;
  f.frame = local_frame ? ExternalForce::Frame::kLocal : ExternalForce::Frame::kWorld;
  f.force_N = force_N;
  f.profile = profile;
  f.start_s = start_s;
  f.duration_s = duration_s;
  f.rise_s = rise_s;
  return f;
}

std::string body_link_name(const Model& model, int body) {
  for (const Frame& frame : model.frames()) {
    if (frame.body == body && frame.placement.isApprox(Eigen::Isometry3d::Identity())) return frame.name;
  }
  throw ConfigError("<model>", "body " + std::to_string(body), "has no frame of its own");
}

namespace {

// Two unit vectors perpendicular to `axis` (unit) and to each other.
void perpendiculars(const Eigen::Vector3d& axis, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d seed = std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = axis.cross(seed).normalized();
  e2 = axis.cross(e1);
}

Eigen::Vector3d random_unit(RandomGenerator& rng) {
  for (;;) {
    const Eigen::Vector3d v(rng.normal(), rng.normal(), rng.normal());
    if (v.norm() > 1e-6) return v.normalized();
  }
}

}  // namespace

PushSpec draw_random_push(RandomGenerator& rng, const Model& model, const CollisionModel& collision,
                          const RandomPushRanges& ranges) {
  std::vector<int> moving;
  for (std::size_t c = 0; c < collision.capsules().size(); ++c) {
    if (collision.capsules()[c].body >= 0) moving.push_back(static_cast<int>(c));
  }
  if (moving.empty()) throw ConfigError("<collision model>", "capsules", "no capsule on a moving link to push on");
  const auto pick = static_cast<std::size_t>(rng.uniform() * static_cast<double>(moving.size()));
  const Capsule& capsule = collision.capsules()[static_cast<std::size_t>(moving[std::min(pick, moving.size() - 1)])];
  PushSpec p;
  p.kind = PushKind::kRandom;
  p.body = capsule.body;
  p.link = body_link_name(model, capsule.body);
  const Eigen::Vector3d span = capsule.p1 - capsule.p0;
  const Eigen::Vector3d axis = span.norm() > 1e-9 ? Eigen::Vector3d(span.normalized()) : Eigen::Vector3d::UnitZ();
  Eigen::Vector3d e1, e2;
  perpendiculars(axis, e1, e2);
  const double along = rng.uniform(), angle = rng.uniform(0.0, 2.0 * std::numbers::pi);
  const Eigen::Vector3d normal = std::cos(angle) * e1 + std::sin(angle) * e2;
  p.point_local = capsule.p0 + along * span + capsule.radius * normal;
  Eigen::Vector3d direction = random_unit(rng);
  if (direction.dot(normal) > 0.0) direction = -direction;  // into the surface
  p.local_frame = true;
  p.magnitude_N = rng.uniform(ranges.min_force_N, ranges.max_force_N);
  p.force_N = p.magnitude_N * direction;
  const auto profile = static_cast<int>(std::min(2.0, std::floor(3.0 * rng.uniform())));
  p.profile = static_cast<ExternalForce::Profile>(profile);
  p.duration_s = rng.uniform(ranges.min_duration_s, ranges.max_duration_s);
  p.rise_s = p.duration_s * rng.uniform(0.1, 1.0);
  return p;
}

PushSpec draw_motion_push(RandomGenerator& rng, const Model& model, const CollisionModel& collision,
                          const MotionFaultRanges& ranges, bool hand_on_tool, const std::string& tool_body,
                          const std::string& tool_frame) {
  RandomPushRanges push_ranges;
  push_ranges.min_force_N = ranges.min_force_N;
  push_ranges.max_force_N = ranges.max_force_N;
  push_ranges.min_duration_s = ranges.min_duration_s;
  push_ranges.max_duration_s = ranges.max_duration_s;
  PushSpec p = draw_random_push(rng, model, collision, push_ranges);
  p.profile = ExternalForce::Profile::kRamp;
  if (!hand_on_tool) return p;
  const Frame& frame = model.frame(model.frame_id(tool_frame));
  p.body = frame.body;
  p.link = tool_frame;
  p.plant_body = tool_body;
  p.plant_point_local = Eigen::Vector3d::Zero();
  p.point_local = frame.placement.translation();
  p.local_frame = false;
  p.force_N = p.magnitude_N * random_unit(rng);
  return p;
}

std::uint64_t name_hash(std::string_view name) {
  std::uint64_t h = 0xCBF29CE484222325ULL;
  for (const char c : name) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001B3ULL;
  }
  return h;
}

PushSpec joint_limit_push(const Model& model, const Data& data, int joint, int toward, double force_N, double duration_s) {
  PushSpec p;
  p.kind = PushKind::kJointLimit;
  p.joint = joint;
  p.toward = toward;
  p.magnitude_N = force_N;
  p.profile = ExternalForce::Profile::kRamp;
  p.rise_s = std::min(0.05, duration_s);
  p.duration_s = duration_s;
  p.local_frame = false;
  const int body = std::min(joint + 1, model.num_bodies() - 1);
  const Eigen::Vector3d point = data.body_placements[static_cast<std::size_t>(body)].translation();
  Eigen::MatrixXd jacobian(3, model.nv());
  body_point_linear_jacobian(model, data, body, point, jacobian);
  const Eigen::Vector3d column = jacobian.col(joint);
  if (column.norm() < 1e-6) return p;  // body -1: the push cannot move the joint from there
  p.body = body;
  p.link = body_link_name(model, body);
  p.force_N = static_cast<double>(toward) * force_N * column.normalized();
  return p;
}

PushSpec wrist_fold_push(const Model& model, const Data& data, const std::string& link, const Eigen::Vector3d& target,
                         double force_N, double duration_s) {
  PushSpec p;
  p.kind = PushKind::kWristFold;
  p.body = model.frame(model.frame_id(link)).body;
  p.link = link;
  p.magnitude_N = force_N;
  p.profile = ExternalForce::Profile::kRamp;
  p.rise_s = std::min(0.05, duration_s);
  p.duration_s = duration_s;
  p.local_frame = false;
  const Eigen::Vector3d origin = data.body_placements[static_cast<std::size_t>(p.body)].translation();
  p.force_N = force_N * (target - origin).normalized();
  return p;
}

namespace {

FaultCase make_case(std::string name, FaultKind kind, FaultSignal signal, double value, int joint, int size = 0) {
  FaultCase c;
  c.name = std::move(name);
  c.spec.kind = kind;
  c.spec.signal = signal;
  c.spec.value = value;
  c.spec.joint = joint;
  c.spec.size = size;
  return c;
}

}  // namespace

std::vector<FaultCase> fault_catalogue(FaultSet set, int dof, std::uint64_t seed) {
  if (set == FaultSet::kNone) return {};
  RandomGenerator rng(seed, 0xFA017);
  auto joint = [&]() { return std::min(dof - 1, static_cast<int>(rng.uniform() * dof)); };
  auto sign = [&]() { return rng.uniform() < 0.5 ? -1.0 : 1.0; };
  const double inf = std::numeric_limits<double>::infinity();
  using K = FaultKind;
  using S = FaultSignal;
  std::vector<FaultCase> all;
  const S per_joint[] = {S::kPosition, S::kVelocity, S::kTorque, S::kCurrent};
  for (S s : per_joint) all.push_back(make_case("nan_" + std::string(to_string(s)), K::kNaN, s, 0.0, joint()));
  for (S s : per_joint) all.push_back(make_case("inf_" + std::string(to_string(s)), K::kInf, s, inf, joint()));
  for (S s : per_joint) all.push_back(make_case("spike_1e6_" + std::string(to_string(s)), K::kAdd, s, sign() * 1e6, joint()));
  all.push_back(make_case("spike_q_0.5rad", K::kAdd, S::kPosition, 0.5, joint()));
  all.push_back(make_case("spike_qd_3rad_s", K::kAdd, S::kVelocity, 3.0, joint()));
  all.push_back(make_case("spike_tau_50Nm", K::kAdd, S::kTorque, 50.0, joint()));
  all.push_back(make_case("offset_q_0.05rad", K::kAdd, S::kPosition, 0.05, joint()));
  all.push_back(make_case("offset_qd_0.2rad_s", K::kAdd, S::kVelocity, 0.2, joint()));
  all.push_back(make_case("offset_tau_5Nm", K::kAdd, S::kTorque, 5.0, joint()));
  all.push_back(make_case("frozen_values", K::kFrozenValues, S::kPosition, 0.0, 0));
  all.push_back(make_case("stale_frame", K::kStaleFrame, S::kPosition, 0.0, 0));
  all.push_back(make_case("sequence_jump", K::kSequenceJump, S::kPosition, 1000.0, 0));
  all.push_back(make_case("stamp_jump", K::kStampJump, S::kPosition, 0.5, 0));
  all.push_back(make_case("stamp_frozen", K::kStampFrozen, S::kPosition, 0.0, 0));
  all.push_back(make_case("short_current_0", K::kShortVector, S::kCurrent, 0.0, 0, 0));
  all.push_back(make_case("short_current_n-1", K::kShortVector, S::kCurrent, 0.0, 0, dof - 1));
  all.push_back(make_case("wrench_spike_1e6N", K::kAdd, S::kWrench, 1e6, 0));
  all.push_back(make_case("wrench_spike_200N", K::kAdd, S::kWrench, 200.0, 0));
  all.push_back(make_case("wrench_nan", K::kNaN, S::kWrench, 0.0, 0));
  all.push_back(make_case("write_refused", K::kWriteRefused, S::kPosition, 0.0, 0));
  // Spikes are one sample in motion (at rest: each of the options' lengths, as before).
  for (FaultCase& c : all) {
    if (c.name.rfind("spike_", 0) == 0 || c.name.rfind("wrench_spike_", 0) == 0) c.motion_cycles = 1;
  }
  // Issue 37's additions (drawn after the older entries so their joints and signs stay as they were).
  auto fixed = [&](FaultCase c, long cycles) {
    c.fixed_cycles = cycles;
    all.push_back(std::move(c));
  };
  for (int periods : {19, 20, 50}) fixed(make_case("stall_" + std::to_string(periods), K::kStall, S::kPosition, periods, 0), 1);
  const int random_stall = std::clamp(1 + static_cast<int>(rng.uniform() * 100.0), 1, 100);
  fixed(make_case("stall_random_" + std::to_string(random_stall), K::kStall, S::kPosition, random_stall, 0), 1);
  fixed(make_case("sequence_jump_1e6", K::kSequenceJump, S::kPosition, 1e6, 0), 1);
  fixed(make_case("offset_tau_50Nm", K::kAdd, S::kTorque, 50.0, joint()), 100);
  fixed(make_case("drift_tau_50Nm", K::kDrift, S::kTorque, 50.0, joint()), 100);
  all.push_back(make_case("wrench_stuck", K::kWrenchStuck, S::kWrench, 0.0, 0));
  all.push_back(make_case("wrench_stale", K::kWrenchStale, S::kWrench, 0.0, 0));
  all.push_back(make_case("wrench_invalid", K::kWrenchInvalid, S::kWrench, 0.0, 0));
  if (set == FaultSet::kAll) return all;
  std::vector<FaultCase> subset;
  for (const FaultCase& c : all) {
    if (c.name == "nan_q" || c.name == "spike_tau_50Nm" || c.name == "stale_frame" || c.name == "short_current_0" ||
        c.name == "wrench_spike_1e6N" || c.name == "write_refused" || c.name == "stall_50" || c.name == "wrench_stuck") {
      subset.push_back(c);
    }
  }
  return subset;
}

}  // namespace phri
