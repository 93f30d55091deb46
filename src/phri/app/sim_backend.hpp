#pragma once
// The simulated arm as a run's backend ("sim"): a phri::SimRobot built from config.plant (the
// robot's description plus the plant's settings), checked against the controller's URDF first
// (app/plant_check.hpp); it takes the live front end's pushes.
#include <phri/app/backend_registry.hpp>

namespace phri {

void register_sim_backend(BackendRegistry& registry);

}  // namespace phri
