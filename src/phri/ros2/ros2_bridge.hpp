#pragma once
// phri::Ros2Bridge: phri on a ROS 2 system without ROS installed: Cyclone DDS with ROS 2's topic
// names ("rt/" + the ROS name), type names (pkg::msg::dds_::Name_, ros2/idl/ros2_messages.idl)
// and QoS (RELIABLE, VOLATILE, KEEP_LAST 10; /tf_static TRANSIENT_LOCAL, KEEP_LAST 1).
//
// One observer of the run (RunOptions::observers: observer()) and one source of commands
// (RunOptions::inputs: input()). Its own thread takes the loop's snapshots and publishes them; the
// control thread only copies a snapshot into a ring (dropped, counted, when the bridge lags), so
// DDS never makes the cycle wait. Inputs are taken by the same thread, checked (InputGate) and
// queued to the loop through the bounded lock-free command ring of a LiveChannel.
//
//   publishes                       type                          content
//   /joint_states                   sensor_msgs/JointState        q, qd, measured joint torque
//   <ns>/joint_commands             sensor_msgs/JointState        effort: desired torque tau_d
//   <ns>/external_torque            sensor_msgs/JointState        effort: the observer's tau_ext
//   <ns>/wrench                     geometry_msgs/WrenchStamped   operator wrench at the end effector, frame "world"
//   <ns>/ee_pose, <ns>/ee_target    geometry_msgs/PoseStamped     end effector and its tracked target, frame "world"
//   /tf                             tf2_msgs/TFMessage            base link -> each link (forward kinematics of q)
//   /tf_static                      tf2_msgs/TFMessage            world -> base link, last link -> end effector
//   <ns>/status                     std_msgs/String               ros2/status_text.hpp
//   subscribes
//   <ns>/target_pose                geometry_msgs/PoseStamped     the end-effector target (ros2/input_gate.hpp)
//   <ns>/event                      std_msgs/String               an event name (config/event.hpp)
//   <ns>/ft_in (settings.ft_in)     geometry_msgs/WrenchStamped   the F/T sensor of another machine (ft_in_robot.hpp)
// Stamps are the wall clock (system_clock) at publication; /joint_states every
// joint_states_decimation cycles, the rest every `decimation` cycles.
#include <phri/app/live_channel.hpp>
#include <phri/app/snapshot_channel.hpp>
#include <phri/config/ros2_settings.hpp>
#include <phri/model/model.hpp>
#include <phri/ros2/ft_in_robot.hpp>
#include <phri/ros2/input_gate.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace phri {

enum class Ros2Topic : std::uint8_t {
  kJointStates, kJointCommands, kExternalTorque, kWrench, kEePose, kEeTarget, kTf, kStatus, kTfStatic
};
inline constexpr int kRos2TopicCount = 9;

struct Ros2BridgeStats {
  std::array<std::uint64_t, kRos2TopicCount> published{};
  std::uint64_t snapshots = 0;          ///< taken from the loop
  std::uint64_t snapshots_dropped = 0;  ///< the loop found the ring full
  std::uint64_t targets = 0, events = 0;  ///< accepted and queued to the loop
  std::uint64_t wrenches = 0;             ///< /phri/ft_in samples accepted
  std::array<std::uint64_t, kInputRefusalCount> refused{};
  std::uint64_t refused_total() const;
};

class Ros2Bridge {
public:
  /// Creates the DDS participant, topics, writers and readers (throws phri::IoError when DDS
  /// refuses). `ee_frame`: the controller's end-effector frame in `model`.
  Ros2Bridge(const Ros2Settings& settings, const Model& model, int ee_frame);
  ~Ros2Bridge();
  Ros2Bridge(const Ros2Bridge&) = delete;
  Ros2Bridge& operator=(const Ros2Bridge&) = delete;

  void start();  ///< the bridge's thread; /tf_static is published here
  void stop();   ///< joins the thread (the last snapshots are published first)

  SnapshotChannel& observer();  ///< RunOptions::observers
  LiveChannel& input();         ///< RunOptions::inputs
  /// The newest /phri/ft_in sample (settings.ft_in), for one reader: FtInRobot.
  TripleBuffer<FtInSample>& ft_in();

  int domain() const;
  const Ros2Settings& settings() const;
  /// What /phri/target_pose is checked against (reach, rate).
  const InputLimits& input_limits() const;
  /// "rt/joint_states sensor_msgs::msg::dds_::JointState_" ... (what a DDS tool sees).
  std::vector<std::string> wire_topics() const;
  /// Counts so far (exact once stop() returned).
  Ros2BridgeStats stats() const;
  /// The DDS name of a ROS 2 topic name ("/joint_states" -> "rt/joint_states").
  static std::string dds_topic_name(std::string_view ros_name);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phri
