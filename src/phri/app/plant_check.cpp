#include <phri/app/plant_check.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/model/model.hpp>
#include <phri/sim/sim_scene.hpp>

#include <string>
#include <vector>

namespace phri {
namespace {

// Joint limits of the URDF and of the plant agree to this (the MJCF copies the URDF's values).
constexpr double kLimitTolerance_rad = 1e-3;

std::string joint_type_name(JointType type) { return type == JointType::kRevolute ? "revolute" : "continuous"; }

// One joint of the controller's URDF against the same joint of the plant's MJCF.
void check_joint_matches_plant(const Joint& joint, const SimScene::ArmJoint& plant, const std::string& urdf,
                               const std::string& mjcf) {
  const std::string where = "joint '" + joint.name + "'";
  // Revolute/continuous joints are hinges in the plant, prismatic ones slides.
  if (joint.type == JointType::kPrismatic && plant.hinge) {
    throw ConfigError(urdf, where, "prismatic in the URDF but a hinge in the plant (" + mjcf + ")");
  }
  if (joint.type != JointType::kPrismatic && !plant.hinge) {
    throw ConfigError(urdf, where, joint_type_name(joint.type) + " in the URDF but a slide in the plant (" + mjcf + ")");
  }
  if (joint.type == JointType::kContinuous || !joint.has_position_limits()) {
    if (plant.limited) {
      throw ConfigError(urdf, where, "unlimited in the URDF but limited to " + format_range(plant.lower, plant.upper) +
                                         " rad in the plant (" + mjcf + ")");
    }
    return;
  }
  if (plant.limited && (joint.lower < plant.lower - kLimitTolerance_rad || joint.upper > plant.upper + kLimitTolerance_rad)) {
    throw ConfigError(urdf, where + " <limit>",
                      "limits " + format_range(joint.lower, joint.upper) + " rad go beyond the plant's range " +
                          format_range(plant.lower, plant.upper) + " (" + mjcf + ")");
  }
}

void check_urdf_matches_plant(const Model& model, const ControllerSettings& controller, const SimRobotConfig& config_plant) {
  const std::vector<SimScene::ArmJoint> plant = SimScene::arm_joints(config_plant);
  const std::string& urdf = controller.urdf_path;
  for (const Joint& joint : model.joints()) {
    const SimScene::ArmJoint* match = nullptr;
    for (const SimScene::ArmJoint& p : plant) {
      if (p.name == joint.name) match = &p;
    }
    if (match == nullptr) {
      throw ConfigError(urdf, "joint '" + joint.name + "'", "not a joint of the plant (" + config_plant.actuators_path + ")");
    }
    check_joint_matches_plant(joint, *match, urdf, config_plant.arm_file());
  }
}

}  // namespace

void check_plant_matches_controller(const ControllerSettings& controller, const SimRobotConfig& plant) {
  const Model model = Model::from_urdf_file(controller.urdf_path, Controller::model_options(controller));
  check_urdf_matches_plant(model, controller, plant);
}

}  // namespace phri
