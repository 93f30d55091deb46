#include <phri/app/mcap_log.hpp>

#include <phri/app/logger.hpp>
#include <phri/core/cdr.hpp>
#include <phri/core/error.hpp>
#include <phri/core/version.hpp>

#include <cmath>
#include <cstring>
#include <fstream>

namespace phri {
namespace {

constexpr const char* kCycleSchema = "phri_msgs/msg/CycleRecord";
constexpr const char* kSeparator = "================================================================================\n";

// The standard messages' ros2msg definitions with their dependencies, as rosbag2 stores them.
const std::string kTimeMsg = "int32 sec\nuint32 nanosec\n";
const std::string kHeaderMsg = "builtin_interfaces/Time stamp\nstring frame_id\n";
const std::string kVector3Msg = "float64 x\nfloat64 y\nfloat64 z\n";

std::string dependency(const char* name, const std::string& text) {
  return std::string(kSeparator) + "MSG: " + name + "\n" + text;
}
std::string header_dependencies() {
  return dependency("std_msgs/Header", kHeaderMsg) + dependency("builtin_interfaces/Time", kTimeMsg);
}
std::string joint_state_definition() {
  return "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n" +
         header_dependencies();
}
std::string pose_stamped_definition() {
  return "std_msgs/Header header\ngeometry_msgs/Pose pose\n" + header_dependencies() +
         dependency("geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n") +
         dependency("geometry_msgs/Point", kVector3Msg) +
         dependency("geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n");
}
std::string wrench_stamped_definition() {
  return "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n" + header_dependencies() +
         dependency("geometry_msgs/Wrench", "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n") +
         dependency("geometry_msgs/Vector3", kVector3Msg);
}

// The bridge's QoS (reliable, volatile, keep last 10), in rosbag2's offered_qos_profiles form.
constexpr const char* kQos =
    "- history: 1\n  depth: 10\n  reliability: 1\n  durability: 2\n  deadline:\n    sec: 0\n    nsec: 0\n"
    "  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
    "  avoid_ros_namespace_conventions: false\n";

struct DefinitionVisitor {
  std::string out;
  void number(const char* name, double) { out += std::string("float64 ") + name + "\n"; }
  void integer(const char* name, std::int64_t) { out += std::string("int64 ") + name + "\n"; }
  template <std::size_t N>
  void joints(const char* name, const std::array<double, N>&, int) {
    out += std::string("float64[] ") + name + "\n";
  }
};

struct EncodeVisitor {
  CdrWriter& cdr;
  void number(const char*, double value) { cdr.put(value); }
  void integer(const char*, std::int64_t value) { cdr.put(value); }
  template <std::size_t N>
  void joints(const char*, const std::array<double, N>& values, int dof) {
    cdr.put_sequence(values.data(), static_cast<std::size_t>(dof));
  }
};

struct DecodeVisitor {
  CdrReader& cdr;
  int dof = -1;
  void number(const char*, double& value) { value = cdr.get<double>(); }
  template <class Integer>
  void integer(const char*, Integer& value) {
    value = static_cast<Integer>(cdr.get<std::int64_t>());
  }
  template <std::size_t N>
  void joints(const char* name, std::array<double, N>& values, int) {
    const auto count = static_cast<int>(cdr.get<std::uint32_t>());
    if (dof < 0) dof = count;
    if (count != dof || count < 1 || count > static_cast<int>(N)) {
      throw IoError(cdr.what(), std::string(name) + " has " + std::to_string(count) + " joints, expected " +
                                       std::to_string(dof) + " (1 to " + std::to_string(N) + ")");
    }
    for (int i = 0; i < count; ++i) values[static_cast<std::size_t>(i)] = cdr.get<double>();
  }
};

void put_header(CdrWriter& cdr, std::uint64_t time_ns, std::string_view frame_id) {
  cdr.put(static_cast<std::int32_t>(time_ns / 1000000000u));
  cdr.put(static_cast<std::uint32_t>(time_ns % 1000000000u));
  cdr.put_string(frame_id);
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ",") + n;
  return out;
}

}  // namespace

std::string cycle_record_definition() {
  DefinitionVisitor v;
  v.out = "# One control cycle of phri: the columns of its CSV log in order (src/phri/config/log_row.hpp), the\n"
          "# per-joint groups as arrays over the arm's joints. Integer codes: metadata record phri_log, key legend.\n";
  visit_log_columns(LogRow{}, kLogMaxJoints, v);
  return v.out;
}

McapLogWriter::McapLogWriter(const LoggerSettings& settings)
    : settings_(settings),
      mcap_(settings.path, {.profile = "ros2", .library = std::string("phri ") + version(),
                            .chunk_bytes = settings.mcap_chunk_bytes, .zstd_level = settings.mcap_zstd_level}) {
  if (settings.ros_topics_every < 1) throw ConfigError(settings.path, "ros_topics_every", "at least 1 (every cycle)");
  const McapWriter::Metadata qos{{"offered_qos_profiles", kQos}};
  const std::string& ns = settings.topic_namespace;
  cycle_ = mcap_.add_channel(mcap_.add_schema(kCycleSchema, "ros2msg", cycle_record_definition()), ns + "/cycle", "cdr", qos);
  const auto joint_state = mcap_.add_schema("sensor_msgs/msg/JointState", "ros2msg", joint_state_definition());
  joint_states_ = mcap_.add_channel(joint_state, "/joint_states", "cdr", qos);
  joint_commands_ = mcap_.add_channel(joint_state, ns + "/joint_commands", "cdr", qos);
  external_torque_ = mcap_.add_channel(joint_state, ns + "/external_torque", "cdr", qos);
  const auto pose = mcap_.add_schema("geometry_msgs/msg/PoseStamped", "ros2msg", pose_stamped_definition());
  ee_pose_ = mcap_.add_channel(pose, ns + "/ee_pose", "cdr", qos);
  ee_target_ = mcap_.add_channel(pose, ns + "/ee_target", "cdr", qos);
  if (settings.has_ft_sensor) {
    const auto wrench = mcap_.add_schema("geometry_msgs/msg/WrenchStamped", "ros2msg", wrench_stamped_definition());
    wrench_ = mcap_.add_channel(wrench, ns + "/wrench", "cdr", qos);
  }
  mcap_.add_metadata("phri_log", {{"legend", Logger::legend_yaml(settings.pfl_links)},
                                  {"dof", std::to_string(settings.dof)},
                                  {"joint_names", joined(settings.joint_names)},
                                  {"csv_header", Logger::header(settings.dof)}});
  buffer_.reserve(4096);
}

void McapLogWriter::write_joint_state(std::uint16_t channel, std::uint64_t time_ns, const LogRow&,
                                      const LogRow::Joints* position, const LogRow::Joints* velocity,
                                      const LogRow::Joints& effort) {
  const auto dof = static_cast<std::size_t>(settings_.dof);
  CdrWriter cdr(buffer_);
  put_header(cdr, time_ns, "");
  cdr.put(static_cast<std::uint32_t>(settings_.joint_names.size()));
  for (const std::string& name : settings_.joint_names) cdr.put_string(name);
  cdr.put_sequence(position != nullptr ? position->data() : nullptr, position != nullptr ? dof : 0);
  cdr.put_sequence(velocity != nullptr ? velocity->data() : nullptr, velocity != nullptr ? dof : 0);
  cdr.put_sequence(effort.data(), dof);
  mcap_.write(channel, time_ns, buffer_.data(), buffer_.size());
}

void McapLogWriter::write_pose(std::uint16_t channel, std::uint64_t time_ns, const LogRow&,
                               const std::array<double, 3>& position, const std::array<double, 4>& q) {
  CdrWriter cdr(buffer_);
  put_header(cdr, time_ns, "world");
  for (double p : position) cdr.put(p);
  for (double c : {q[1], q[2], q[3], q[0]}) cdr.put(c);  // ROS order x, y, z, w
  mcap_.write(channel, time_ns, buffer_.data(), buffer_.size());
}

void McapLogWriter::write(const LogRow& row) {
  const double t = std::isfinite(row.time_s) && row.time_s > 0.0 ? row.time_s : 0.0;
  const auto time_ns = static_cast<std::uint64_t>(std::llround(t * 1e9));
  {
    CdrWriter cdr(buffer_);
    visit_log_columns(row, settings_.dof, EncodeVisitor{cdr});
    mcap_.write(cycle_, time_ns, buffer_.data(), buffer_.size());
  }
  if (rows_++ % settings_.ros_topics_every != 0) return;
  write_joint_state(joint_states_, time_ns, row, &row.q, &row.qd, row.tau_s);
  write_joint_state(joint_commands_, time_ns, row, nullptr, nullptr, row.tau_d);
  write_joint_state(external_torque_, time_ns, row, nullptr, nullptr, row.tau_ext);
  write_pose(ee_pose_, time_ns, row, row.ee_position, row.ee_quaternion);
  write_pose(ee_target_, time_ns, row, row.target_position, row.target_quaternion);
  if (settings_.has_ft_sensor) {
    CdrWriter cdr(buffer_);
    put_header(cdr, time_ns, "ft_sensor");
    for (double w : row.ft_wrench) cdr.put(w);
    mcap_.write(wrench_, time_ns, buffer_.data(), buffer_.size());
  }
}

McapLogInfo read_mcap_log(const std::string& path, const std::function<void(const LogRow&, int dof)>& on_row) {
  McapLogInfo info;
  bool has_cycle_channel = false;
  McapVisitor visitor;
  visitor.on_channel = [&](const McapChannel& c) {
    if (c.schema != nullptr && c.schema->name == kCycleSchema) has_cycle_channel = true;
  };
  visitor.on_metadata = [&](const std::string& name, const std::map<std::string, std::string>& m) {
    if (name != "phri_log") return;
    if (const auto legend = m.find("legend"); legend != m.end()) info.legend = legend->second;
    if (const auto header = m.find("csv_header"); header != m.end()) info.csv_header = header->second;
  };
  visitor.on_message = [&](const McapChannel& c, const McapMessage& m) {
    if (c.schema == nullptr || c.schema->name != kCycleSchema) return;
    CdrReader cdr(m.data, m.size, path + ": " + c.topic + " message " + std::to_string(m.sequence));
    LogRow row;
    DecodeVisitor decode{cdr};
    visit_log_columns(row, kLogMaxJoints, decode);
    if (info.rows == 0) info.dof = decode.dof;
    if (decode.dof != info.dof) throw IoError(path, "cycle records with " + std::to_string(decode.dof) +
                                                        " and " + std::to_string(info.dof) + " joints");
    ++info.rows;
    on_row(row, info.dof);
  };
  info.file = read_mcap(path, visitor);
  if (!has_cycle_channel) {
    throw IoError(path, std::string("an MCAP file without a ") + kCycleSchema + " channel (not a phri log)");
  }
  return info;
}

McapLogInfo export_mcap_log_csv(const std::string& mcap_path, const std::string& csv_path, bool legend) {
  std::FILE* out = std::fopen(csv_path.c_str(), "wb");
  if (out == nullptr) throw IoError(csv_path, std::string("cannot create: ") + std::strerror(errno));
  std::vector<char> line(Logger::kMaxCsvLineBytes + 1);
  bool ok = true;
  bool first = true;
  McapLogInfo info;
  try {
    info = read_mcap_log(mcap_path, [&](const LogRow& row, int dof) {
      if (first) {
        first = false;
        const std::string header = Logger::header(dof) + "\n";
        ok = ok && std::fwrite(header.data(), 1, header.size(), out) == header.size();
      }
      char* end = Logger::csv_line(row, dof, line.data(), line.data() + Logger::kMaxCsvLineBytes);
      *end++ = '\n';
      const auto size = static_cast<std::size_t>(end - line.data());
      ok = ok && std::fwrite(line.data(), 1, size, out) == size;
    });
    if (first && !info.csv_header.empty()) {  // no rows: the header the logger wrote
      ok = ok && std::fprintf(out, "%s\n", info.csv_header.c_str()) > 0;
    }
  } catch (...) {
    std::fclose(out);
    throw;
  }
  ok = std::fclose(out) == 0 && ok;
  if (!ok) throw IoError(csv_path, "writing the CSV failed (disk full?)");
  if (legend && !info.legend.empty()) {
    std::ofstream(Logger::legend_path_for(csv_path), std::ios::binary) << info.legend;
  }
  return info;
}

bool is_mcap_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, sizeof(magic));
  return in.gcount() == 8 && std::memcmp(magic, "\x89MCAP0\r\n", 8) == 0;
}

}  // namespace phri
