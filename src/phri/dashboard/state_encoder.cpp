#include <phri/dashboard/state_encoder.hpp>

#include <phri/config/event.hpp>
#include <phri/app/fsm.hpp>
#include <phri/app/live_gain.hpp>
#include <phri/control/compliance_mode.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/robot/low_level_mode.hpp>
#include <phri/safety/state_supervisor.hpp>
#include <phri/safety/wrench_supervisor.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {
namespace {

using nlohmann::json;

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json placement(const Eigen::Isometry3d& m) {
  const Eigen::Quaterniond r(m.rotation());
  const Eigen::Vector3d& p = m.translation();
  return json::array({p.x(), p.y(), p.z(), r.w(), r.x(), r.y(), r.z()});
}

template <std::size_t N>
json first(const std::array<double, N>& a, int n) {
  return json(std::vector<double>(a.begin(), a.begin() + std::min<int>(n, static_cast<int>(N))));
}

json pose(const std::array<double, 3>& p, const std::array<double, 4>& q) {
  return {{"p", json(p)}, {"q", json(q)}};
}

// The name of a model body: its own link frame (placement identity).
std::string body_name(const Model& model, int body) {
  for (const Frame& f : model.frames()) {
    if (f.type == FrameType::kLink && f.body == body && f.placement.isApprox(Eigen::Isometry3d::Identity())) return f.name;
  }
  return model.joint(body).name;
}

json joints_json(const Model& model) {
  json joints = json::array();
  for (int i = 0; i < model.nq(); ++i) {
    const Joint& j = model.joint(i);
    joints.push_back({{"name", j.name},
                      {"lower", j.has_position_limits() ? json(j.lower) : json(nullptr)},
                      {"upper", j.has_position_limits() ? json(j.upper) : json(nullptr)},
                      {"velocity_limit", j.velocity_limit},
                      {"body", body_name(model, i)}});
  }
  return joints;
}

json capsules_json(const CollisionModel* collision) {
  json capsules = json::array();
  if (!collision) return capsules;
  for (const Capsule& c : collision->capsules()) {
    capsules.push_back({{"link", c.link}, {"body", c.body}, {"p0", vec(c.p0)}, {"p1", vec(c.p1)}, {"radius", c.radius}});
  }
  return capsules;
}

json controls_json() {
  json events = json::array();
  for (std::string_view name : kEventNames) events.push_back(std::string(name));
  json gains = json::array();
  for (int g = 0; g < kLiveGainCount; ++g) {
    const LiveGainRange r = range_of(static_cast<LiveGain>(g));
    gains.push_back({{"name", std::string(kLiveGainNames[static_cast<std::size_t>(g)])},
                     {"min", r.min}, {"max", r.max}, {"mode_value", r.mode_value}});
  }
  return {{"events", events}, {"gains", gains}};
}

}  // namespace

StateEncoder::StateEncoder(const Model& model, const CollisionModel* collision, const StateEncoderSettings& settings)
    : model_(model), collision_(collision), settings_(settings), data_(model), q_(Eigen::VectorXd::Zero(model.nq())) {
  if (collision_) collision_data_.emplace(model, *collision_);
}

std::string StateEncoder::model_json() const {
  const json controls = controls_json();
  json j = {{"dof", model_.nq()},
            {"joints", joints_json(model_)},
            {"base", placement(model_.base_placement())},
            {"capsules", capsules_json(collision_)},
            {"events", controls["events"]},
            {"gains", controls["gains"]},
            {"push_max_N", settings_.push_max_N},
            {"touch_threshold", settings_.touch_threshold},
            {"release_threshold", settings_.release_threshold}};
  json contact = json::array();
  if (settings_.body_regions && collision_) {
    for (const std::string& link : PowerForceLimitMonitor::monitored_links(*collision_)) {
      contact.push_back({{"link", link}, {"region", settings_.body_regions->for_link(link).name}});
    }
  }
  j["contact"] = contact;
  return j.dump();
}

std::string StateEncoder::frame_json(const LiveSnapshot& s) {
  const LogRow& r = s.row;
  const int n = std::min(s.dof, model_.nq());
  for (int i = 0; i < n; ++i) q_[i] = r.q[static_cast<std::size_t>(i)];
  forward_kinematics(model_, data_, q_);
  json qd_ratio = json::array(), margin = json::array(), bodies = json::array();
  for (int i = 0; i < n; ++i) {
    const Joint& jt = model_.joint(i);
    qd_ratio.push_back(std::abs(r.qd[static_cast<std::size_t>(i)]) / jt.velocity_limit);
    const double half = 0.5 * (jt.upper - jt.lower);
    margin.push_back(jt.has_position_limits() ? std::clamp(std::min(q_[i] - jt.lower, jt.upper - q_[i]) / half, 0.0, 1.0) : 1.0);
  }
  for (int b = 0; b < model_.num_bodies(); ++b) bodies.push_back(placement(data_.body_placements[static_cast<std::size_t>(b)]));
  json j = {{"t", r.time_s}, {"cycle", r.cycle}, {"paused", s.paused}, {"q", first(r.q, n)},
            {"qd_ratio", qd_ratio}, {"margin", margin}, {"tau_d", first(r.tau_d, n)}, {"tau_s", first(r.tau_s, n)},
            {"ee", pose(r.ee_position, r.ee_quaternion)}, {"target", pose(r.target_position, r.target_quaternion)},
            {"err_pos_mm", 1e3 * r.error_position_m}, {"err_ori_deg", r.error_orientation_rad * 180.0 / std::numbers::pi},
            {"wrench", json(r.wrench)}, {"wrench_norm", r.wrench_norm},
            {"mode", std::string(to_string(static_cast<ComplianceMode>(r.compliance_mode)))}, {"touched", r.touched != 0},
            {"loop", std::string(to_string(static_cast<LowLevelMode>(r.low_level_loop)))},
            {"fsm", r.fsm_state >= 0 ? std::string(to_string(static_cast<FsmState>(r.fsm_state))) : std::string("none")},
            {"safety", std::string(to_string(static_cast<SupervisorState>(r.safety_state)))}, {"safety_code", r.safety_state},
            {"ft", std::string(to_string(static_cast<WrenchStatus>(r.ft_status)))}, {"ft_code", r.ft_status},
            {"event", r.event >= 0 ? json(std::string(to_string(static_cast<Event>(r.event)))) : json(nullptr)},
            {"cycle_us", 1e6 * r.cycle_time_s}, {"overruns", s.overruns}, {"bodies", bodies}};
  j["contact_ratio"] = std::vector<double>(s.contact_ratio.begin(), s.contact_ratio.begin() + std::clamp(s.contact_links, 0, kLiveMaxContactLinks));
  j["gains"] = {{"stiffness_scale", r.stiffness_scale}, {"ee_gamma", s.ee_gamma_override},
                {"posture_gamma", s.posture_gamma_override}, {"posture_stiffness", s.posture_stiffness}};
  j["push"] = nullptr;
  if (s.push.body >= 0 && s.push.body < model_.num_bodies()) {
    const Eigen::Vector3d point = data_.body_placements[static_cast<std::size_t>(s.push.body)] * s.push.point_local;
    j["push"] = {{"body", s.push.body}, {"point", vec(point)}, {"force", vec(s.push.force_world)},
                 {"magnitude", s.push.force_world.norm()}};
  }
  j["collision"] = nullptr;
  if (collision_ && collision_->num_pairs() > 0) {
    compute_collision_distances(model_, data_, *collision_, *collision_data_, false);
    Eigen::Index p = 0;
    const double d = collision_data_->distance.minCoeff(&p);
    const CapsulePair& pair = collision_->pairs()[static_cast<std::size_t>(p)];
    j["collision"] = {{"first", collision_->capsules()[static_cast<std::size_t>(pair.first)].link},
                      {"second", collision_->capsules()[static_cast<std::size_t>(pair.second)].link},
                      {"distance_mm", 1e3 * d}, {"a", vec(collision_data_->point_first.col(p))},
                      {"b", vec(collision_data_->point_second.col(p))}};
  }
  return j.dump();
}

}  // namespace phri
