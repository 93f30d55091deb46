#include <phri/app/sim_backend.hpp>

#include <phri/app/plant_check.hpp>
#include <phri/sim/sim_robot.hpp>

namespace phri {
namespace {

class SimBackend final : public Backend {
public:
  explicit SimBackend(const Config& config) : robot_(config.plant) {}
  RobotInterface& robot() override { return robot_; }
  PushInput* pushes() override { return &robot_; }
  const GroundTruth* ground_truth() const override { return &robot_; }

private:
  SimRobot robot_;
};

}  // namespace

void register_sim_backend(BackendRegistry& registry) {
  registry.add("sim", [](const BackendRequest& request) -> std::unique_ptr<Backend> {
    check_plant_matches_controller(request.config.controller, request.config.plant);
    return std::make_unique<SimBackend>(request.config);
  });
}

}  // namespace phri
