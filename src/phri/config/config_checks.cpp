#include <phri/config/config_checks.hpp>
#include <phri/robot/actuator_table.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/collision_model.hpp>

#include <Eigen/SVD>

#include <cmath>
#include <string>
#include <vector>

namespace phri {
namespace {

void check_end_effector_frame(const Model& model, const Config& config) {
  const std::string& name = config.controller.end_effector_frame;
  if (!model.has_frame(name)) {
    throw ConfigError(config.source, "robot.end_effector_frame", "no frame '" + name + "' in " + config.controller.urdf_path);
  }
  const int body = model.frame(model.frame_id(name)).body;
  if (body != model.nq() - 1) {
    const std::string what = body < 0 ? "is not moved by any joint" : "is upstream of the last joint '" +
                                                                          model.joint(model.nq() - 1).name + "'";
    throw ConfigError(config.source, "robot.end_effector_frame",
                      "'" + name + "' " + what + ": the end-effector task and the F/T sensor need a frame that every joint moves");
  }
}

// A posture of the run: one value per joint, within the URDF's limits.
void check_within_limits(const Model& model, const std::vector<double>& q, const std::string& source,
                         const std::string& key) {
  for (int i = 0; i < model.nq() && i < static_cast<int>(q.size()); ++i) {
    const Joint& joint = model.joint(i);
    const double value = q[static_cast<std::size_t>(i)];
    if (joint.has_position_limits() && (value < joint.lower || value > joint.upper)) {
      throw ConfigError(source, key + "[" + std::to_string(i) + "]",
                        format_general(value, 6) + " rad is beyond " + joint.name + "'s limits " +
                            format_range(joint.lower, joint.upper) + " (URDF)");
    }
  }
}

// A posture of the run, clear of self-collision: every pair at least the damper's safety distance apart.
void check_clear_of_collision(const Model& model, const CollisionModel& collision, const std::vector<double>& q,
                              double safety_distance, const std::string& source, const std::string& key) {
  Data data(model);
  CollisionData distances(model, collision);
  forward_kinematics(model, data, Eigen::Map<const Eigen::VectorXd>(q.data(), static_cast<Eigen::Index>(q.size())));
  compute_collision_distances(model, data, collision, distances, false);
  for (int k = 0; k < collision.num_pairs(); ++k) {
    if (distances.distance[k] >= safety_distance) continue;
    const CapsulePair& pair = collision.pairs()[static_cast<std::size_t>(k)];
    throw ConfigError(source, key,
                      "in self-collision: capsules of " + collision.capsules()[static_cast<std::size_t>(pair.first)].link +
                          " and " + collision.capsules()[static_cast<std::size_t>(pair.second)].link + " are " +
                          format_general(distances.distance[k], 4) +
                          " m apart, below controller.qp.collision.safety_distance_m " + format_general(safety_distance, 4));
  }
}

}  // namespace

void check_config_against_robot(const Config& config) {
  const ControllerSettings& settings = config.controller;
  {
    // The plain URDF first: the frame the options hang the F/T sensor and payloads on must be right.
    ModelOptions chain_only;  // the chain of the settings, without the F/T frame and the payloads
    chain_only.base_link = settings.base_link;
    chain_only.tip_link = settings.tip_link;
    chain_only.locked_joints = settings.locked_joints;
    const Model plain = Model::from_urdf_file(settings.urdf_path, chain_only);
    check_end_effector_frame(plain, config);
  }
  const Model model = Model::from_urdf_file(settings.urdf_path, Controller::model_options(settings));
  const std::vector<std::pair<std::string, const std::vector<double>*>> postures = {
      {"plant.initial.q_rad", &config.plant.initial_q_rad},
      {"fsm.startup.home_q_rad", &config.fsm.startup.home_q_rad},
      {"fsm.static.posture_q_rad", &config.fsm.static_scenario.posture_q_rad}};
  for (const auto& [key, q] : postures) check_within_limits(model, *q, config.source, key);
  const std::optional<CollisionModel> fitted_or_file = Controller::collision_model(settings, model);
  if (!fitted_or_file) return;
  const CollisionModel& collision = *fitted_or_file;
  for (const auto& [key, q] : postures) {
    if (static_cast<int>(q->size()) != model.nq()) continue;  // sizes: checked where they are read
    check_clear_of_collision(model, collision, *q, settings.qp.collision.safety_distance, config.source, key);
  }
}

std::vector<std::string> config_warnings(const Config& config) {
  std::vector<std::string> warnings;
  const ControllerSettings& settings = config.controller;
  // Each actuators.yaml default in use (a generic drive's data a maker does not publish), one line each.
  if (!settings.actuators_path.empty()) {
    for (std::string& notice : ActuatorTable::from_yaml_file(settings.actuators_path).notices(settings.actuators_path)) {
      warnings.push_back(std::move(notice));
    }
  }
  const double threshold = settings.qp.singular_value_threshold;
  if (threshold <= 0.0) return warnings;
  const Model model = Model::from_urdf_file(settings.urdf_path, Controller::model_options(settings));
  if (!model.has_frame(settings.end_effector_frame)) return warnings;  // refused elsewhere
  Data data(model);
  const int frame = model.frame_id(settings.end_effector_frame);
  Eigen::MatrixXd jacobian(6, model.nv());
  const std::vector<std::pair<std::string, const std::vector<double>*>> postures = {
      {"fsm.startup.home_q_rad", &config.fsm.startup.home_q_rad},
      {"fsm.static.posture_q_rad", &config.fsm.static_scenario.posture_q_rad}};
  for (const auto& [key, q] : postures) {
    if (static_cast<int>(q->size()) != model.nq()) continue;
    const Eigen::VectorXd posture = Eigen::Map<const Eigen::VectorXd>(q->data(), model.nq());
    forward_kinematics(model, data, posture);
    update_frame_placements(model, data);
    frame_jacobian(model, data, frame, ReferenceFrame::kLocalWorldAligned, jacobian);
    const double sigma_min = Eigen::JacobiSVD<Eigen::MatrixXd>(jacobian).singularValues().minCoeff();
    if (sigma_min >= threshold) continue;
    warnings.push_back(config.source + ": " + key + ": near a kinematic singularity (smallest singular value of the " +
                       settings.end_effector_frame + " Jacobian " + format_general(sigma_min, 3) + " < " +
                       format_general(threshold, 3) +
                       "): the end-effector task holds its weak direction only through the posture; a better-"
                       "conditioned posture holds the pose stiffer");
  }
  return warnings;
}

}  // namespace phri
