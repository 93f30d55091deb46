#pragma once
// The Gen3 plant at the paper demo's posture (phri::SimRobot, 5 % mismatch, friction, noise) and a
// Controller, driven read -> step -> write as app/run_session.cpp does, with a hook that may
// corrupt the state the controller sees (the plant keeps its own, true, sensors for its built-in
// loops) and control-thread stalls (the plant runs on the last accepted command). What it records
// is the plant's truth: the worst speed ratio, the joint-limit excess, refused writes.
#include <phri/control/controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include "gen3_settings.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace phri::test {

using Corrupt = std::function<void(long cycle, RobotState&)>;

// URDF limits of the Gen3's limited joints (2, 4, 6), robots/kinova_gen3/gen3.urdf.
constexpr double kLimit2 = 2.24, kLimit4 = 2.57, kLimit6 = 2.09;

class SafetyRig {
public:
  SafetyRig(ComplianceMode mode, LowLevelMode loop, std::vector<ExternalForce> pushes = {},
            const std::function<void(ControllerSettings&)>& edit = {})
      : config_(make_config(std::move(pushes))), robot_(config_), cycle_(settings(mode, loop, edit)), command_(7) {
    for (int i = 0; i < 7; ++i) velocity_limit_[i] = robot_.plant_actuators()[i].velocity_limit_rad_s;
  }

  static SimRobotConfig make_config(std::vector<ExternalForce> pushes) {
    SimRobotConfig c = SimRobotConfig::from_yaml_file(std::string(PHRI_SOURCE_DIR) + "/configs/plant_gen3.yaml");
    c.initial_q_rad = {0, 0.58, 3.14, -1.84, 0, 0.85, 1.57};
    c.mismatch.enabled = true;
    c.disturbances = std::move(pushes);
    return c;
  }
  static ControllerSettings settings(ComplianceMode mode, LowLevelMode loop,
                                     const std::function<void(ControllerSettings&)>& edit) {
    ControllerSettings s = gen3_controller_settings(mode, loop);
    if (edit) edit(s);
    return s;
  }

  // Runs `seconds`; the hook (if any) corrupts the state of chosen cycles; `each` after every cycle.
  void run(double seconds, const Corrupt& corrupt = {}, const std::function<void()>& each = {}) {
    const long n = std::lround(seconds / robot_.period_s());
    for (long k = 0; k < n; ++k, ++cycle_count_) {
      const RobotState& state = robot_.read();
      if (corrupt) {
        seen_ = state;
        corrupt(cycle_count_, seen_);
        cycle_.step(seen_, targets_, command_);
      } else {
        cycle_.step(state, targets_, command_);
      }
      targets_.clear();
      if (robot_.write(command_) != WriteStatus::kOk) {
        ++refused_;
        last_refused_s_ = robot_.state().time_s;
        if (cycle_.answer_refused_write(robot_.state(), command_) && robot_.write(command_) != WriteStatus::kOk) ++refused_;
      }
      record();
      if (each) each();
    }
  }
  // The control thread stalls for `periods`: the plant runs them on its last accepted command.
  void stall(long periods) {
    for (long k = 0; k < periods; ++k) {
      robot_.read();
      record();
    }
  }
  void record() {
    const auto& t = robot_.truth();
    for (int i = 0; i < 7; ++i) speed_ratio_ = std::max(speed_ratio_, std::abs(t.qd_rad_s[i]) / velocity_limit_[i]);
    limit_excess_ = std::max({limit_excess_, std::abs(t.q_rad[1]) - kLimit2, std::abs(t.q_rad[3]) - kLimit4,
                              std::abs(t.q_rad[5]) - kLimit6});
  }
  const Eigen::VectorXd& q() const { return robot_.truth().q_rad; }
  const Eigen::VectorXd& qd() const { return robot_.truth().qd_rad_s; }

  SimRobotConfig config_;
  SimRobot robot_;
  Controller cycle_;
  RobotCommand command_;
  ControllerTargets targets_{7};
  RobotState seen_;
  Eigen::VectorXd velocity_limit_ = Eigen::VectorXd::Zero(7);
  long cycle_count_ = 0;
  long refused_ = 0;
  double last_refused_s_ = -1.0;  ///< plant time of the latest refused write (-1: none)
  double speed_ratio_ = 0.0;
  double limit_excess_ = -std::numeric_limits<double>::infinity();
};

// Largest joint distance between two postures.
inline double distance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).cwiseAbs().maxCoeff(); }

// The direction in which joint `joint` (0-based) moves the origin of `link`, at the demo posture.
inline Eigen::Vector3d joint_direction(const std::string& link, int joint) {
  Model model = Model::from_urdf_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf");
  Data data(model);
  Eigen::VectorXd q0(7);
  q0 << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
  forward_kinematics(model, data, q0);
  update_frame_placements(model, data);
  const Eigen::Vector3d point = data.frame_placements[static_cast<std::size_t>(model.frame_id(link))].translation();
  Eigen::MatrixXd jacobian(3, 7);
  body_point_linear_jacobian(model, data, model.frame(model.frame_id(link)).body, point, jacobian);
  return jacobian.col(joint).normalized();
}

}  // namespace phri::test
