#pragma once
// The Gen3 controller the tests drive: the robot bundle robots/kinova_gen3 (files, frames, end of
// arm, dead band, H(z)) with the library's defaults for the rest (the paper's demo values), one
// home for the tests that build it.
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller_settings.hpp>

#include <string>

namespace phri::test {

inline const RobotBundle& gen3_bundle() {
  static const RobotBundle bundle = RobotBundle::from_folder(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3");
  return bundle;
}

inline ControllerSettings gen3_controller_settings(ComplianceMode mode = ComplianceMode::kNullSpace,
                                                   LowLevelMode loop = LowLevelMode::kPosition) {
  ControllerSettings s;
  gen3_bundle().apply_to(s);
  s.initial_compliance = mode;
  s.initial_loop = loop;
  return s;
}

}  // namespace phri::test
