#pragma once
// phri::WrenchPublisher: the publishing end of /phri/ft_in, for `phri ft-bridge` on the machine the
// F/T sensor is plugged into (the paper's NUC): geometry_msgs/WrenchStamped on
// <namespace>/ft_in ("rt/phri/ft_in"), RELIABLE (matches BEST_EFFORT and RELIABLE readers),
// VOLATILE, KEEP_LAST 10, stamped with the sample's own time. Same DDS configuration as the bridge
// (domain, discovery: ros2/dds_config.hpp).
#include <phri/config/ros2_settings.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <string>

namespace phri {

class WrenchPublisher {
public:
  /// Throws phri::IoError when DDS refuses. `frame_id`: the sensor's frame.
  WrenchPublisher(const Ros2Settings& settings, const std::string& frame_id);
  ~WrenchPublisher();
  WrenchPublisher(const WrenchPublisher&) = delete;
  WrenchPublisher& operator=(const WrenchPublisher&) = delete;

  /// Fx, Fy, Fz [N], Mx, My, Mz [N.m]; `stamp_ns`: wall-clock (system_clock) time of the sample.
  bool publish(const std::array<double, 6>& wrench, std::int64_t stamp_ns);
  std::uint64_t published() const { return published_; }
  /// Readers matched so far (a subscriber has discovered us).
  int matched() const;
  int domain() const { return domain_id_; }
  const std::string& dds_topic() const { return topic_; }

private:
  int domain_id_ = 0;
  int domain_ = 0, participant_ = 0, writer_ = 0;
  std::string topic_, frame_id_;
  std::uint64_t published_ = 0;
};

}  // namespace phri
