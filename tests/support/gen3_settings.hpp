#pragma once
// The Gen3 controller the tests drive: the robot files of robots/kinova_gen3 with the library's
// defaults (the paper's demo values), one home for the tests that build it.
#include <phri/control/controller_settings.hpp>

#include <string>

namespace phri::test {

inline ControllerSettings gen3_controller_settings(ComplianceMode mode = ComplianceMode::kNullSpace,
                                                   LowLevelMode loop = LowLevelMode::kPosition) {
  const std::string gen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";
  ControllerSettings s;
  s.urdf_path = gen3 + "gen3.urdf";
  s.actuators_path = gen3 + "actuators.yaml";
  s.collision_path = gen3 + "collision.yaml";
  s.initial_compliance = mode;
  s.initial_loop = loop;
  return s;
}

}  // namespace phri::test
