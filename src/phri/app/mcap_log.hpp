#pragma once
// phri's binary log: an MCAP file as rosbag2 writes one (core/mcap_writer.hpp; profile ros2, schemas
// ros2msg, messages cdr), so `ros2 bag`, Foxglove and PlotJuggler open it. Its topics:
//
//   <ns>/cycle             phri_msgs/msg/CycleRecord   every column of the CSV log, one message per
//                                                      cycle (cycle_record_definition(); exported
//                                                      back to the CSV bit for bit)
//   /joint_states          sensor_msgs/msg/JointState  position q, velocity qd, effort tau_s (measured)
//   <ns>/joint_commands    sensor_msgs/msg/JointState  effort tau_d (desired torque)
//   <ns>/external_torque   sensor_msgs/msg/JointState  effort tau_ext (the observer's estimate)
//   <ns>/wrench            geometry_msgs/msg/WrenchStamped  the F/T sample in frame "ft_sensor"
//                                                      (only with a sensor)
//   <ns>/ee_pose, <ns>/ee_target  geometry_msgs/msg/PoseStamped  the end effector and its target,
//                                                      frame "world"
//
// the ROS 2 bridge's names and types (ros2/ros2_bridge.hpp; ns defaults to /phri), the standard ones
// every `ros_topics_every` cycles. Time stamps (message log time and header stamps) are the robot's
// time of the row. The legend of the integer codes, the joint names and the CSV header are in the
// file's metadata record "phri_log".
#include <phri/config/log_row.hpp>
#include <phri/config/logger_settings.hpp>
#include <phri/core/mcap_reader.hpp>
#include <phri/core/mcap_writer.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace phri {

/// The ros2msg definition of phri_msgs/msg/CycleRecord (the fields in CSV column order).
std::string cycle_record_definition();

class McapLogWriter {
public:
  /// Creates settings.path (IoError when it cannot), its schemas, channels and metadata.
  explicit McapLogWriter(const LoggerSettings& settings);
  /// Encodes one row (writer thread; allocation-free once its buffers have grown).
  void write(const LogRow& row);
  /// Writes the open chunk and flushes the file (a later crash keeps everything so far).
  void flush() { mcap_.flush(); }
  /// The summary and footer; IoError if any write failed.
  void close() { mcap_.close(); }
  const McapWriterStats& stats() const { return mcap_.stats(); }

private:
  void write_joint_state(std::uint16_t channel, std::uint64_t time_ns, const LogRow& row, const LogRow::Joints* position,
                         const LogRow::Joints* velocity, const LogRow::Joints& effort);
  void write_pose(std::uint16_t channel, std::uint64_t time_ns, const LogRow& row, const std::array<double, 3>& position,
                  const std::array<double, 4>& quaternion_wxyz);

  LoggerSettings settings_;
  McapWriter mcap_;
  std::uint16_t cycle_ = 0, joint_states_ = 0, joint_commands_ = 0, external_torque_ = 0, wrench_ = 0, ee_pose_ = 0,
                ee_target_ = 0;
  std::vector<std::uint8_t> buffer_;
  std::int64_t rows_ = 0;
};

struct McapLogInfo {
  int dof = 0;                  ///< joints per group (from the records)
  std::uint64_t rows = 0;       ///< cycle records read
  std::string legend;           ///< the integer codes' legend (YAML), as Logger::legend_yaml
  std::string csv_header;       ///< the CSV header the logger wrote (Logger::header)
  McapReadSummary file;         ///< truncated, complete, chunks...
};

/// Every <ns>/cycle record of a phri MCAP log, in order, as the LogRow the logger was given (the
/// columns past `dof` zero). IoError on a file that is not a phri MCAP log or a record that does not
/// decode; a truncated file is read up to its last complete chunk (info.file.truncated).
McapLogInfo read_mcap_log(const std::string& path, const std::function<void(const LogRow&, int dof)>& on_row);

/// Writes the CSV log the logger would have written for the same rows (header and lines, bit for
/// bit) from a phri MCAP log, and with `legend` its <csv>.legend.yaml. Returns what was read.
McapLogInfo export_mcap_log_csv(const std::string& mcap_path, const std::string& csv_path, bool legend);

/// True when `path` starts with the MCAP magic (false for a CSV, or a file that cannot be read: the
/// reader that opens it then says why).
bool is_mcap_file(const std::string& path);

}  // namespace phri
