#pragma once
// The closed loop the controller benchmarks run: the simulated Gen3 (its noise, friction and a 5 %
// model mismatch) at a working posture, pushed on the elbow (30 N) and three seconds later on the
// tool (15 N), half-sine pushes of 1 s every 6 s, for `duration_s`.
#include <phri/sim/sim_robot.hpp>

#include <string>

inline phri::SimRobotConfig pushed_gen3_plant(double duration_s) {
  phri::SimRobotConfig plant = phri::SimRobotConfig::from_yaml_file(std::string(PHRI_SOURCE_DIR) + "/configs/plant_gen3.yaml");
  plant.initial_q_rad = {0, 0.58, 3.14, -1.84, 0, 0.85, 1.57};
  plant.mismatch.enabled = true;
  for (double start = 1.0; start < duration_s; start += 6.0) {
    phri::ExternalForce elbow;
    elbow.body = "forearm_link";
    elbow.force_N = Eigen::Vector3d(0, 30, 0);
    elbow.profile = phri::ExternalForce::Profile::kHalfSine;
    elbow.start_s = start;
    elbow.duration_s = 1.0;
    plant.disturbances.push_back(elbow);
    phri::ExternalForce hand = elbow;
    hand.body = "tool";
    hand.force_N = Eigen::Vector3d(0, -15, 0);
    hand.start_s = start + 3.0;
    plant.disturbances.push_back(hand);
  }
  return plant;
}
