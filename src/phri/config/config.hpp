#pragma once
// phri::Config: ONE YAML file per run (configs/demo.yaml is the reference, every key commented),
// turned into the settings of every piece of the run:
//
//   const phri::Config config = phri::Config::from_yaml_file("configs/demo.yaml");  // throws phri::ConfigError
//   phri::SimRobot robot(config.plant);
//   phri::Controller cycle(config.controller);
//   phri::Fsm fsm(config.fsm, cycle);                    // config.fsm.timeline: the `events:` list
//   phri::Gamepad gamepad(config.gamepad);  gamepad.start();
//   std::optional<phri::Logger> logger;  if (config.logging_enabled) logger.emplace(config.logging);
//   phri::LoopClock clock(robot.period_s(), config.run.pacing);
//   phri::RobotCommand command(robot.dof());
//   phri::LogRow row;
//   while (robot.state().time_s < config.run.duration_s && !fsm.finished()) {
//     const phri::RobotState& state = robot.read();
//     for (phri::Event e; gamepad.poll(e);) fsm.post(e);
//     cycle.step(state, fsm.update(state.time_s, state, cycle), command);
//     robot.write(command);
//     if (logger) { phri::fill_log_row(row, state, cycle, fsm); row.cycle_time_s = ...; logger->push(row); }
//     clock.wait_next();
//   }
//
// Schema (top-level sections; all but `robot` and `plant` optional, absent keys keep the defaults
// of the settings structs, which follow the paper where it gives a value):
//   robot:       either a robot bundle's folder (robots/<robot>, see config/robot_bundle.hpp), or
//                urdf, actuators, collision ('' for none), end_effector_frame (required),
//                ft_sensor_offset_m (default 0), payloads [{name, frame, mass_kg, com_m,
//                inertia_kgm2}] (default none: the library knows no arm's end of arm) -> ControllerSettings
//                (a bundle also sets the plant's arm, drives, F/T sensor and tool; `plant:` may
//                then be left out, the plant's defaults and the bundle's home posture applying)
//   plant:       either `file: plant_gen3.yaml` plus any keys of that file's `plant:` section to
//                override (maps merged key by key, lists replaced), or the whole section inline
//                                                                             -> SimRobotConfig
//   controller:  period_s, observer_gain, compliance_deadband {large_Nm, small_Nm, per_joint_Nm},
//                compliance {initial_mode, stiffness/damping/weights, touch/release thresholds},
//                qp {limits, joint_limits {influence_fraction, safety_fraction, amortization},
//                collision {influence_distance_m, safety_distance_m, approach_speed_m_s, amortization},
//                ...}, wrench {tool_mass_kg, tool_com_m, bias_samples}       -> ControllerSettings
//   low_level:   torque_loop (start-up hands over to it), custom {transfer_gain, integral_gain,
//                integral_leak, integral_limit_fraction, friction_compensation,
//                rotor_inertia_compensation}                                 -> ControllerSettings
//   fsm:         first_scenario, stiffness_step, rest_speed_rad_s, startup {...}, static {...},
//                dynamic {...}, brake {...}                                 -> FsmSettings
//   events:      [{at: seconds, event: name}] (names: config/event.hpp)          -> FsmSettings::timeline
//   logging:     enabled, path, buffer_rows, legend                           -> LoggerSettings
//   gamepad:     enabled, poll_interval_ms, trigger_press, trigger_release    -> GamepadSettings
//   run:         duration_s, pacing (real_time | lockstep)                    -> RunSettings
//   ros2:        enabled, domain, namespace, joint_states_decimation, decimation, subscribe,
//                max_input_rate_hz, max_reach_m, discovery (loopback | network), ft_in -> Ros2Settings
//
// Validation at load: unknown keys, duplicate keys, explicit nulls, wrong types, values outside
// their physical range and inconsistent pairs are a phri::ConfigError naming the file and the key
// path (the checks against the robot, config/config_checks.hpp, too; the plant against the URDF when the simulator is built, app/plant_check.hpp), e.g. "controller.qp.collision.safety_distance_m"
// (d_s must be < d_i), "controller.compliance.release_threshold" (must be < touch_threshold),
// "events[3].event". Input files (urdf, actuators, collision, plant file) are relative to the
// folder of the YAML that names them and must exist; the log path (an output) is relative to the
// working directory, so that a run never writes into configs/.
//
// The compliance modes fix the gammas (0 or 1 per task, control/compliance_controller.hpp), so the
// file has no gamma keys.
#include <phri/config/fsm_settings.hpp>
#include <phri/config/gamepad_settings.hpp>
#include <phri/config/logger_settings.hpp>
#include <phri/config/ros2_settings.hpp>
#include <phri/config/run_settings.hpp>
#include <phri/config/sim_robot_config.hpp>
#include <phri/control/controller_settings.hpp>

#include <string>

namespace phri {

struct Config {
  static Config from_yaml_file(const std::string& path);
  /// The same with the robot bundle in `robot_folder` (robots/<robot>/robot.yaml) in place of
  /// whatever robot the file names (`phri run --robot DIR`); empty: the file's own.
  static Config from_yaml_file(const std::string& path, const std::string& robot_folder);
  /// `base_dir` resolves relative input files; `source_name` stands for the file in errors.
  static Config from_yaml_string(const std::string& yaml, const std::string& source_name, const std::string& base_dir);

  std::string source;              ///< the file it came from
  /// The arm's name for figures and summaries: its bundle's `name`, else its URDF's file stem.
  std::string robot_name;
  ControllerSettings controller;
  SimRobotConfig plant;
  FsmSettings fsm;                 ///< with the `events:` timeline, sorted by time
  bool logging_enabled = true;
  LoggerSettings logging;
  /// logging.format: auto (the default): resolve_log_format decides once the run's length is known.
  bool log_format_auto = true;
  GamepadSettings gamepad;
  RunSettings run;
  Ros2Settings ros2;
  /// The body regions each link may meet (ISO/TS 15066), for the run's power-and-force-limiting
  /// figures (log, summary): `body_regions`, else the QP constraint's
  /// (controller.qp.power_force_limit); empty: none configured, no figures.
  std::optional<BodyRegionMap> body_regions;
};

/// Runs longer than this log to MCAP when logging.format is auto (a CSV grows by ~1.7 MB/s).
inline constexpr double kCsvLogMaxAutoDurationS = 60.0;

/// Settles logging.format once the run's duration is final (command-line overrides applied): auto
/// picks MCAP for a path ending in .mcap or a run longer than kCsvLogMaxAutoDurationS, CSV otherwise;
/// a path ending in .csv or .mcap then takes the chosen format's extension. Returns the format.
LogFormat resolve_log_format(Config& config);

/// The region `name` of a regions file (configs/iso_ts_15066_regions.yaml's form); ConfigError
/// naming the file's regions when it has none of that name.
BodyRegion body_region_from_file(const std::string& file, const std::string& name);

}  // namespace phri
