#pragma once
// phri::FtInRobot: the F/T sensor of a run taken from /phri/ft_in (a sensor on another machine,
// `phri ft-bridge` there) instead of the arm's own. It wraps the run's robot: read() returns the
// robot's state with the wrench fields replaced by the newest sample the ROS 2 bridge received
// (TripleBuffer: wait-free, no allocation), so the controller's WrenchSupervisor checks it like any
// sensor: the sequence counts new samples, the stamp is the robot time the sample was received at
// (robot time of this cycle - its age on the host's steady clock), so a peer that stops publishing
// goes stale after stale_s, bit-identical samples freeze, out-of-range values and a wrench the
// observer does not see drop the source (reported, latched), and a dropped source is never a push.
// Needs real-time pacing: in lockstep robot time outruns the wall clock and the sensor is stale.
#include <phri/core/triple_buffer.hpp>
#include <phri/robot/robot_interface.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace phri {

/// One /phri/ft_in sample as the bridge hands it over.
struct FtInSample {
  std::array<double, 6> wrench{};  ///< Fx, Fy, Fz [N], Mx, My, Mz [N.m], the sensor's frame
  std::uint64_t count = 0;         ///< samples accepted so far (0: none yet)
  std::int64_t received_ns = 0;    ///< steady_clock time the bridge took it
  std::int64_t stamp_ns = 0;       ///< the publisher's header stamp (its clock) [ns]
};

class FtInRobot : public RobotInterface {
public:
  /// `ages_capacity`: how many sample ages (at the first cycle that sees each) are kept.
  FtInRobot(RobotInterface& inner, TripleBuffer<FtInSample>& source, std::size_t ages_capacity = 1 << 16);

  int dof() const override { return inner_.dof(); }
  double period_s() const override { return inner_.period_s(); }
  const RobotState& read() override;
  WriteStatus write(const RobotCommand& command) override { return inner_.write(command); }

  /// Age of each new sample at the cycle that first read it [s] (the F/T round trip from the
  /// bridge's take to the controller), in order, up to ages_capacity.
  const std::vector<double>& ages_s() const { return ages_; }
  /// The same from the publisher's stamp (system clock: meaningful on one machine or with
  /// synchronised clocks): the whole trip, sensor read -> DDS -> bridge -> cycle [s].
  const std::vector<double>& stamp_ages_s() const { return stamp_ages_; }
  std::uint64_t samples_seen() const { return seen_; }

private:
  RobotInterface& inner_;
  TripleBuffer<FtInSample>& source_;
  RobotState state_;
  std::uint64_t last_count_ = 0;
  std::uint64_t seen_ = 0;
  double stamp_s_ = 0.0;  // robot time the newest sample came
  std::vector<double> ages_, stamp_ages_;
};

}  // namespace phri
