#pragma once
// The simulated plant against the controller's URDF (MuJoCo compiles the plant's MJCF, so this
// check lives with the simulator's backend, not in the configuration library): the same joints,
// hinges where the plant has hinges, no limit wider than the plant's, no 'continuous' joint the
// plant limits. Each a phri::ConfigError naming the URDF and the joint.
#include <phri/config/sim_robot_config.hpp>
#include <phri/control/controller_settings.hpp>

namespace phri {

void check_plant_matches_controller(const ControllerSettings& controller, const SimRobotConfig& plant);

}  // namespace phri
