#pragma once
// A plant whose joint friction differs from the nominal table (actuators.yaml) by a seeded random
// fraction, for the friction-identification acceptance check (issue 7) and for torque-tracking
// runs with friction model error. Per joint, independently:
//
//   coulomb' = coulomb (1 + f u1),   viscous' = viscous (1 + f u2),   u1, u2 ~ U(-1, 1)
//   static'  = coulomb' (static / coulomb) (1 + f u3),  u3 ~ U(0, 1)   (static' >= coulomb', as
//              the plant requires; nominal static / coulomb = 1 on the Gen3)
//
// so with f = 0.2 each coefficient is off by up to 20 %, and stiction sits up to 20 % above the
// Coulomb level (the paper found them close enough to use one value; the plant may not).
// Same seed, same plant (phri::RandomGenerator is platform independent).
#include <phri/robot/actuator_table.hpp>
#include <phri/config/sim_robot_config.hpp>

#include <cstdint>
#include <vector>

namespace phri {

/// Overrides for SimRobotConfig::actuator_overrides; `fraction` in [0, 0.9].
std::vector<SimRobotConfig::ActuatorOverride> perturbed_friction_overrides(const ActuatorTable& nominal,
                                                                           double fraction, std::uint64_t seed);

}  // namespace phri
