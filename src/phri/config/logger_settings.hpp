#pragma once
// The logger's settings (app/logger.hpp), read from a run YAML's `logging:`; the ring's bound
// follows from the row's size (config/log_row.hpp).
#include <phri/config/log_row.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace phri {

/// Memory bound of the log ring: at most 100 MiB of rows waiting for the writer thread. The ring
/// only absorbs the writer's stalls; 131072 rows of sizeof(LogRow) (~700 B) are 2 min at 1 kHz,
/// and a larger ring only costs memory (4194304 rows took 2.9 GB).
inline constexpr std::size_t kLogRingMaxBytes = std::size_t{100} << 20;

/// Largest ring size within kLogRingMaxBytes (a power of two: the ring rounds its size up to one).
constexpr std::size_t log_ring_max_rows() {
  std::size_t rows = 2;
  while (2 * rows * sizeof(LogRow) <= kLogRingMaxBytes) rows *= 2;
  return rows;
}

/// The log's file format: CSV (one text line per cycle, for short runs and spreadsheets) or MCAP
/// (app/mcap_log.hpp: ROS 2 messages in zstd chunks, ~10x smaller, read by ros2 bag, Foxglove and
/// PlotJuggler; `phri log export --csv` turns it back into the CSV).
enum class LogFormat { kCsv, kMcap };

struct LoggerSettings {
  std::string path = "phri_log.csv";  ///< log file (truncated); its folder must exist
  LogFormat format = LogFormat::kCsv;
  int dof = kLogMaxJoints;            ///< joints written per group (<= kLogMaxJoints)
  std::size_t capacity_rows = 16384;  ///< ring size (rounded up to a power of two), <= log_ring_max_rows()
  bool write_legend = true;           ///< write the <path>.legend.yaml sidecar
  int writer_sleep_ms = 2;            ///< writer's pause when the ring is empty
  /// The links of the pfl_link column, in index order (the legend names them; the run fills it).
  std::vector<std::string> pfl_links;

  // MCAP only (app/mcap_log.hpp)
  std::vector<std::string> joint_names;       ///< sensor_msgs/JointState's names
  bool has_ft_sensor = false;                 ///< log <ns>/wrench
  std::string topic_namespace = "/phri";      ///< the ROS 2 bridge's namespace
  int ros_topics_every = 10;                  ///< the standard ROS topics every N cycles (100 Hz, as the bridge's joint states); the cycle record: every cycle
  std::size_t mcap_chunk_bytes = 1 << 20;     ///< uncompressed bytes per chunk: at most this much is lost on a crash
  int mcap_zstd_level = 3;                    ///< chunk compression level (0: stored; higher levels gain < 1 % on these rows)
};

}  // namespace phri
