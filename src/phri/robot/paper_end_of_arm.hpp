#pragma once
// The paper's end-of-arm setup on the Kinova Gen3, the one place in code that holds its numbers:
// the library's defaults (the plant's F/T sensor and tool, the controller's payloads, the wrench
// estimator's tool) read them from here; configs/plant_gen3.yaml and configs/demo.yaml state the
// same values for a run, with their sources. (The robot-bundle work moves them into the robot's
// own files.)
//   flange -> F/T measuring frame 0.065 m: adapter 0.03 m + Bota mounting-to-wrench 0.035 m [BOTA]
//   adapter + sensor body 0.26931 kg: adapter 0.12 [BOTA] + sensor mounting 0.14931 [BOTA, unverified]
//   tool below the sensor (DS4 gamepad and printed mount) 0.3 kg (ESTIMATE, as in the plant file)
#include <Eigen/Core>

namespace phri {

/// A rigid body given by its mass, centre of mass and principal moments of inertia about it.
struct RigidBodyData {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d principal_inertia_kgm2 = Eigen::Vector3d::Zero();
};

struct PaperEndOfArm {
  /// Flange -> F/T sensor measuring frame, along the flange's z axis [m].
  static constexpr double kSensorOffset_m = 0.065;
  /// F/T adapter and sensor body, flange side (not measured by the sensor); COM in the flange frame.
  static RigidBodyData ft_adapter_and_sensor() {
    return {0.26931, Eigen::Vector3d(0.0, 0.0, 0.03), Eigen::Vector3d(2.0e-4, 2.0e-4, 2.2e-4)};
  }
  /// The tool below the sensor; COM in the sensor frame.
  static RigidBodyData tool() { return {0.3, Eigen::Vector3d(0.0, 0.0, 0.05), Eigen::Vector3d(3.4e-4, 7.3e-4, 8.9e-4)}; }
};

}  // namespace phri
