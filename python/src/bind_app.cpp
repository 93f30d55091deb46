// phri/app for Python: the run configuration (Config, one YAML per run), events and the FSM that
// turns them into ControllerTargets, the CSV logger, and run_session (the `phri run` loop, with its
// summary), which runs with the GIL released and prints through Python's sys.stdout.
#include "bindings.hpp"
#include "python_stream.hpp"

#include <phri/app/loop_clock.hpp>
#include <phri/app/mcap_log.hpp>
#include <phri/config/config.hpp>
#include <phri/app/run_session.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/robot/ground_truth.hpp>

#include <filesystem>
#include <sstream>

namespace phri::python {
namespace {

void bind_fsm(py::module_& m) {
  bind_enum<Event, kEventCount>(m, "Event", "What an operator or a timeline asks of the FSM (names as in the YAML timeline).");
  bind_enum<FsmState, 4>(m, "FsmState", "startup, static, dynamic, stopped.");
  py::enum_<Scenario>(m, "Scenario", "The demo's scenarios.")
      .value("static", Scenario::kStatic)
      .value("dynamic", Scenario::kDynamic);
  py::class_<TimedEvent>(m, "TimedEvent", "An event of a scripted timeline at `time_s` of robot time.")
      .def(py::init([](double t, Event e) { return TimedEvent{t, e}; }), py::arg("time_s"), py::arg("event"))
      .def_readwrite("time_s", &TimedEvent::time_s)
      .def_readwrite("event", &TimedEvent::event);
  py::class_<StartupSettings>(m, "StartupSettings", "The FSM's start-up move to the home posture.")
      .def(py::init<>())
      .def_readwrite("enabled", &StartupSettings::enabled)
      .def_readwrite("home_q_rad", &StartupSettings::home_q_rad)
      .def_readwrite("max_joint_speed_rad_s", &StartupSettings::max_joint_speed_rad_s)
      .def_readwrite("tolerance_rad", &StartupSettings::tolerance_rad)
      .def_readwrite("timeout_s", &StartupSettings::timeout_s);
  py::class_<FsmSettings>(m, "FsmSettings", "The demo FSM (configs/demo.yaml `fsm:` and `events:`).")
      .def(py::init<>())
      .def_readwrite("startup", &FsmSettings::startup)
      .def_readwrite("first_scenario", &FsmSettings::first_scenario)
      .def_readwrite("torque_loop", &FsmSettings::torque_loop, "Start-up hands over to it; toggle_loop's torque side.")
      .def_readwrite("stiffness_step", &FsmSettings::stiffness_step)
      .def_readwrite("rest_speed_rad_s", &FsmSettings::rest_speed_rad_s)
      .def_readwrite("timeline", &FsmSettings::timeline, "Scripted events (a list: assign a new one).");
  py::class_<Fsm>(m, "Fsm", "The demo's state machine: events in, ControllerTargets out, once per period.")
      .def(py::init<const FsmSettings&, const Controller&>(), py::arg("settings"), py::arg("controller"),
           py::keep_alive<1, 3>(), "`controller`: the one this FSM drives (kept alive with it).")
      .def("post", py::overload_cast<Event>(&Fsm::post), py::arg("event"), "Queues an event for the next update (False when the queue is full).")
      .def("update", &Fsm::update, py::arg("time_s"), py::arg("state"), py::arg("controller"),
           py::return_value_policy::reference_internal, "This period's targets (before controller.step).")
      .def_property_readonly("targets", &Fsm::targets, py::return_value_policy::reference_internal)
      .def_property_readonly("state", &Fsm::state)
      .def_property_readonly("braking", &Fsm::braking)
      .def_property_readonly("finished", &Fsm::finished, "`stop` was handled and the arm is at rest.")
      .def_property_readonly("startup_complete", &Fsm::startup_complete)
      .def_property_readonly("last_event_code", &Fsm::last_event_code)
      .def_property_readonly("events_handled", &Fsm::events_handled)
      .def_property_readonly("static_pose", &Fsm::static_pose, "The static scenario's end-effector pose (4 x 4).");
}

void bind_logger(py::module_& m) {
  py::enum_<LogFormat>(m, "LogFormat", "csv: a text line per cycle; mcap: ROS 2 messages in zstd chunks (ros2 bag, "
                                        "Foxglove, PlotJuggler; load_log reads both).")
      .value("csv", LogFormat::kCsv)
      .value("mcap", LogFormat::kMcap);
  py::class_<LoggerSettings>(m, "LoggerSettings", "The log of a run (CSV or MCAP).")
      .def(py::init<>())
      .def_readwrite("path", &LoggerSettings::path)
      .def_readwrite("format", &LoggerSettings::format)
      .def_readwrite("joint_names", &LoggerSettings::joint_names, "MCAP: sensor_msgs/JointState's joint names.")
      .def_readwrite("has_ft_sensor", &LoggerSettings::has_ft_sensor, "MCAP: log <ns>/wrench.")
      .def_readwrite("topic_namespace", &LoggerSettings::topic_namespace)
      .def_readwrite("ros_topics_every", &LoggerSettings::ros_topics_every,
                     "MCAP: the standard ROS topics every N cycles (the cycle record: every cycle).")
      .def_readwrite("dof", &LoggerSettings::dof)
      .def_readwrite("capacity_rows", &LoggerSettings::capacity_rows)
      .def_readwrite("write_legend", &LoggerSettings::write_legend)
      .def_readwrite("pfl_links", &LoggerSettings::pfl_links, "The links of the pfl_link column (the legend names them).");
  py::class_<LoggerStats>(m, "LoggerStats", "What the logger wrote and dropped.")
      .def_readonly("pushed", &LoggerStats::pushed)
      .def_readonly("dropped", &LoggerStats::dropped)
      .def_readonly("written", &LoggerStats::written)
      .def_readonly("write_error", &LoggerStats::write_error);
  py::class_<Logger>(m, "Logger", "One row per cycle, CSV or MCAP, written off the control thread (load it with phri.load_log).")
      .def(py::init<const LoggerSettings&>(), py::arg("settings"), "Opens the file; ConfigError when it cannot be created.")
      .def("close", &Logger::close, py::call_guard<py::gil_scoped_release>(), "Drains the ring, closes the file.")
      .def("stats", &Logger::stats, "Counters so far.")
      .def("summary", &Logger::summary, "One line: rows written, dropped, queue depth, throughput.")
      .def_property_readonly("path", &Logger::path)
      .def_property_readonly("legend_path", &Logger::legend_path)
      .def_static("header", &Logger::header, py::arg("dof"), "The CSV header line for `dof` joints.")
      .def_static("legend_yaml", &Logger::legend_yaml, py::arg("pfl_links") = std::vector<std::string>{},
                  "The legend of the integer columns, as YAML (`pfl_links`: the pfl_link column's link names).");
}

void bind_config(py::module_& m) {
  py::enum_<LoopClock::Pacing>(m, "Pacing", "lockstep: as fast as possible; real_time: one period per cycle.")
      .value("lockstep", LoopClock::Pacing::kLockstep)
      .value("real_time", LoopClock::Pacing::kRealTime);
  py::class_<RunSettings>(m, "RunSettings", "The `run:` section: duration and pacing.")
      .def(py::init<>())
      .def_readwrite("duration_s", &RunSettings::duration_s)
      .def_readwrite("pacing", &RunSettings::pacing);
  py::class_<BodyRegion>(m, "BodyRegion", "An ISO/TS 15066 body region: k [N/m], m_H [kg], F_QS [N], transient factor.")
      .def_readwrite("name", &BodyRegion::name)
      .def_readwrite("stiffness_N_per_m", &BodyRegion::stiffness_N_per_m)
      .def_readwrite("mass_kg", &BodyRegion::mass_kg)
      .def_readwrite("quasi_static_force_N", &BodyRegion::quasi_static_force_N)
      .def_readwrite("transient_factor", &BodyRegion::transient_factor);
  py::class_<BodyRegionMap>(m, "BodyRegionMap", "The region each link may meet: `region`, or its own in `links`.")
      .def_readwrite("region", &BodyRegionMap::region)
      .def_readwrite("links", &BodyRegionMap::links)
      .def("for_link", &BodyRegionMap::for_link, py::arg("link"), py::return_value_policy::copy,
           "The region the named link may meet (its own, else `region`).");
  py::class_<Config>(m, "Config", "ONE YAML per run (configs/demo.yaml documents every key), as the settings of each piece.")
      .def_static("from_yaml_file",
                  [](const std::filesystem::path& path, const std::optional<std::filesystem::path>& robot) {
                    return Config::from_yaml_file(path.string(), robot ? robot->string() : std::string());
                  },
                  py::arg("path"), py::arg("robot") = py::none(),
                  "ConfigError naming the file and the key path; robot: a robot bundle's folder in place of the file's robot.")
      .def_static("from_yaml_string", &Config::from_yaml_string, py::arg("yaml"), py::arg("source_name"), py::arg("base_dir"))
      .def_readwrite("source", &Config::source)
      .def_readwrite("controller", &Config::controller)
      .def_readwrite("plant", &Config::plant)
      .def_readwrite("fsm", &Config::fsm)
      .def_readwrite("logging_enabled", &Config::logging_enabled)
      .def_readwrite("logging", &Config::logging)
      .def_readwrite("log_format_auto", &Config::log_format_auto,
                     "logging.format is auto: resolve_log_format decides by the run's duration.")
      .def_readwrite("run", &Config::run)
      .def_readwrite("body_regions", &Config::body_regions, "The body regions the run is measured against, or None.");
}

void bind_run_session(py::module_& m) {
  py::class_<PhaseMark>(m, "PhaseMark", "A named span of a run, from start_s.")
      .def(py::init([](double start, std::string name) { return PhaseMark{start, std::move(name)}; }), py::arg("start_s"),
           py::arg("name"))
      .def_readwrite("start_s", &PhaseMark::start_s)
      .def_readwrite("name", &PhaseMark::name);
  py::class_<RunOptions>(m, "RunOptions", "What run_session runs: duration, pacing, status line, named phases.")
      .def(py::init<>())
      .def_readwrite("duration_s", &RunOptions::duration_s)
      .def_readwrite("real_time", &RunOptions::real_time)
      .def_readwrite("status_line", &RunOptions::status_line)
      .def_readwrite("phases", &RunOptions::phases);
  py::class_<PhaseSummary>(m, "PhaseSummary", "One row of the end-of-run table.")
      .def_readonly("name", &PhaseSummary::name)
      .def_readonly("start_s", &PhaseSummary::start_s)
      .def_readonly("end_s", &PhaseSummary::end_s)
      .def_readonly("ee_position_error_max_mm", &PhaseSummary::ee_position_error_max_mm)
      .def_readonly("ee_position_error_rms_mm", &PhaseSummary::ee_position_error_rms_mm)
      .def_readonly("ee_error_true", &PhaseSummary::ee_error_true, "True: the ee errors are from the plant's true state.")
      .def_readonly("qp_task_position_error_rms_mm", &PhaseSummary::qp_task_position_error_rms_mm)
      .def_readonly("wrench_norm_max", &PhaseSummary::wrench_norm_max)
      .def_readonly("cycle_median_us", &PhaseSummary::cycle_median_us);
  py::class_<ContactLinkSummary>(m, "ContactLinkSummary", "One link's power-and-force-limiting figures over a run.")
      .def_readonly("link", &ContactLinkSummary::link)
      .def_readonly("region", &ContactLinkSummary::region)
      .def_readonly("max_ratio", &ContactLinkSummary::max_ratio)
      .def_readonly("speed_at_max_m_s", &ContactLinkSummary::speed_at_max_m_s)
      .def_readonly("reflected_mass_at_max_kg", &ContactLinkSummary::reflected_mass_at_max_kg)
      .def_readonly("permissible_speed_at_max_m_s", &ContactLinkSummary::permissible_speed_at_max_m_s)
      .def_readonly("max_speed_m_s", &ContactLinkSummary::max_speed_m_s)
      .def_readonly("max_energy_J", &ContactLinkSummary::max_energy_J)
      .def_readonly("time_above_s", &ContactLinkSummary::time_above_s);
  py::class_<RunSummary>(m, "RunSummary", "What run_session measured.")
      .def_readonly("cycles", &RunSummary::cycles)
      .def_readonly("simulated_s", &RunSummary::simulated_s)
      .def_readonly("wall_s", &RunSummary::wall_s)
      .def_readonly("cycle_median_us", &RunSummary::cycle_median_us)
      .def_readonly("cycle_p99_us", &RunSummary::cycle_p99_us)
      .def_readonly("overruns", &RunSummary::overruns)
      .def_readonly("refused_writes", &RunSummary::refused_writes)
      .def_readonly("safe_hold", &RunSummary::safe_hold)
      .def_readonly("safe_hold_reason", &RunSummary::safe_hold_reason)
      .def_readonly("phases", &RunSummary::phases)
      .def_readonly("contact", &RunSummary::contact, "Per link with a capsule (empty: no body regions).")
      .def_readonly("contact_true_state", &RunSummary::contact_true_state);
  m.def("run_session",
        [](RobotInterface& robot, Controller& controller, Fsm& fsm, Logger* logger, const RunOptions& options,
           const std::optional<BodyRegionMap>& body_regions) {
          PythonStream out;
          RunOptions run = options;
          if (body_regions) run.body_regions = &*body_regions;
          if (run.ground_truth == nullptr) run.ground_truth = dynamic_cast<const GroundTruth*>(&robot);
          const py::gil_scoped_release release;
          return run_session(robot, controller, fsm, nullptr, logger, run, out);
        },
        py::arg("robot"), py::arg("controller"), py::arg("fsm"), py::arg("logger") = nullptr, py::arg("options") = RunOptions{},
        py::arg("body_regions") = std::nullopt,
        "The `phri run` loop (read, FSM, step, write, log) for options.duration_s of robot time, GIL released; "
        "progress lines go to sys.stdout. A simulated robot is the summary's ground truth; with body_regions, "
        "the power-and-force-limiting figures (log pfl_ columns, summary.contact).");
  m.def("contact_links", [](const Controller& controller) {
        return controller.collision() ? PowerForceLimitMonitor::monitored_links(*controller.collision()) : std::vector<std::string>{};
      }, py::arg("controller"), "The links the power-and-force-limiting figures cover (those with a capsule, but the base).");
  m.def("run_summary_text", [](const RunSummary& summary) {
        std::ostringstream text;
        print_run_summary(summary, text);
        return text.str();
      }, py::arg("summary"), "The end-of-run report (markdown), as `phri run` prints it.");
  m.def("resolve_log_format", &resolve_log_format, py::arg("config"),
        "Settles config.logging.format once the run's duration is final (auto: mcap over 60 s or for a .mcap path) "
        "and gives the path that format's extension.");
  m.def("export_log_csv", [](const std::filesystem::path& mcap, const std::filesystem::path& csv) {
        const py::gil_scoped_release release;
        return export_mcap_log_csv(mcap.string(), csv.string(), true).rows;
      }, py::arg("mcap"), py::arg("csv"),
      "An MCAP log back to the CSV the run would have written (every column bit for bit) and its legend; returns "
      "the rows written (`phri log export --csv`).");
}

}  // namespace

void bind_app(py::module_& m) {
  bind_fsm(m);
  bind_logger(m);
  bind_config(m);
  bind_run_session(m);
}

}  // namespace phri::python
