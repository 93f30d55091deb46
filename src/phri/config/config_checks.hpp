#pragma once
// The checks of a run configuration that need the robot it names, run by Config's loaders once
// every section is parsed (each a phri::ConfigError naming the key path, or the robot file and
// its element):
//   * robot.end_effector_frame moved by every joint (a frame upstream of the last joint, or the
//     base, cannot carry the end-effector task nor the F/T sensor);
//   * the postures the run starts from or goes to (plant.initial.q_rad, fsm.startup.home_q_rad,
//     fsm.static.posture_q_rad) within the URDF's joint limits and clear of self-collision: no
//     capsule pair closer than controller.qp.collision.safety_distance_m.
// The plant's MJCF against the URDF needs MuJoCo: the simulator's backend checks it
// (app/plant_check.hpp) before the run.
#include <phri/config/config.hpp>

#include <string>
#include <vector>

namespace phri {

void check_config_against_robot(const Config& config);

/// What the configuration allows but the user should know, one line each: the actuators.yaml
/// defaults in use (ActuatorTable::notices: keys a maker does not publish, left out), the postures above
/// near a kinematic singularity (the end-effector Jacobian's smallest singular value below
/// controller.qp.singular_value_threshold, where the task gives its weak directions to the posture).
std::vector<std::string> config_warnings(const Config& config);

}  // namespace phri
