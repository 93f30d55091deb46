#pragma once
// phri::PushInput: a push on the arm from outside the control loop (the dashboard's drag-to-push):
// a force at a point of a link, held for a while unless renewed. A simulated arm takes it
// (phri::SimRobot); a real arm has none. The run loop gets one from the backend that built the
// robot (RunOptions::pushes), so nothing above the robot interface needs to know which robot it is.
#include <Eigen/Core>

#include <string>

namespace phri {

class PushInput {
public:
  virtual ~PushInput() = default;
  PushInput() = default;
  PushInput(const PushInput&) = delete;
  PushInput& operator=(const PushInput&) = delete;

  /// The push target carrying the URDF link `link`, for push(); -1 when the arm has no such body.
  /// May allocate (called before the loop).
  virtual int push_target(const std::string& link) const = 0;
  /// From the next read() on: `force_world_N` [N, world axes] at `point_m` [m, the target's frame],
  /// for `hold_s` of robot time from the latest state's time. Replaces the previous push; target
  /// -1 ends it. No allocation, no throw (called in the cycle).
  virtual void push(int target, const Eigen::Vector3d& point_m, const Eigen::Vector3d& force_world_N, double hold_s) = 0;
};

}  // namespace phri
