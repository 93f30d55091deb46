// phri/experiments for Python: the paper's evaluations as the CLI runs them. Each takes an options
// object (files default to the shipped ones, found in data_dir()), runs with the GIL released and
// prints its progress through sys.stdout (progress=False: silent), and returns a result object; the
// run_*_command functions do what `phri experiment ...` does (files, figure, table) and return its
// exit status.
#include "bindings.hpp"
#include "python_stream.hpp"

#include <phri/experiments/drop_test.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/safety_fuzz.hpp>
#include <phri/experiments/torque_tracking.hpp>
#include <phri/experiments/torque_tracking_sweep.hpp>

namespace phri::python {
namespace {

// Relative input files of an experiment's options, found like the CLI finds them (locate).
template <class Options>
Options located(Options options, std::initializer_list<std::string Options::*> files) {
  for (std::string Options::*file : files) options.*file = locate(options.*file);
  return options;
}

// Calls `run(options, stream)` with the GIL released; the stream is Python's stdout or none.
template <class Result, class Options, class Run>
Result run_released(const Options& options, bool progress, Run run) {
  PythonStream out;
  const py::gil_scoped_release release;
  return run(options, progress ? &out : nullptr);
}

void bind_friction(py::module_& m) {
  using O = FrictionIdentificationOptions;
  py::class_<O>(m, "FrictionIdentificationOptions", "`phri identify-friction`: one joint at a time at constant current.")
      .def(py::init([] { return located(O{}, {&O::plant_config_path, &O::urdf_path, &O::figure_script}); }))
      .def_readwrite("plant_config_path", &O::plant_config_path)
      .def_readwrite("urdf_path", &O::urdf_path)
      .def_readwrite("output_dir", &O::output_dir, "CSV, YAML, markdown go here; empty: no files.")
      .def_readwrite("figure_script", &O::figure_script, "Empty: no figure.")
      .def_readwrite("friction_perturbation", &O::friction_perturbation)
      .def_readwrite("seed", &O::seed)
      .def_readwrite("joints", &O::joints, "1-based joint numbers.")
      .def_readwrite("speed_levels", &O::speed_levels)
      .def_readwrite("min_speed_rad_s", &O::min_speed_rad_s)
      .def_readwrite("max_speed_fraction", &O::max_speed_fraction)
      .def_readwrite("static_bisection_steps", &O::static_bisection_steps);
  py::class_<JointFrictionEstimate>(m, "JointFrictionEstimate", "Identified vs plant vs nominal friction of one joint.")
      .def_readonly("joint", &JointFrictionEstimate::joint, "1-based.")
      .def_readonly("name", &JointFrictionEstimate::name)
      .def_readonly("identified", &JointFrictionEstimate::identified)
      .def_readonly("plant", &JointFrictionEstimate::plant)
      .def_readonly("nominal", &JointFrictionEstimate::nominal)
      .def_readonly("offset_Nm", &JointFrictionEstimate::offset_Nm)
      .def_readonly("residual_rms_Nm", &JointFrictionEstimate::residual_rms_Nm)
      .def_readonly("levels_used", &JointFrictionEstimate::levels_used)
      .def("coulomb_error", &JointFrictionEstimate::coulomb_error, "Relative error of the identified Coulomb level.")
      .def("viscous_error", &JointFrictionEstimate::viscous_error, "Relative error of the identified viscous coefficient.")
      .def("static_error", &JointFrictionEstimate::static_error, "Relative error of the identified static level.");
  py::class_<FrictionIdentificationResult>(m, "FrictionIdentificationResult", "Per-joint estimates and the files written.")
      .def_readonly("joints", &FrictionIdentificationResult::joints)
      .def_readonly("simulated_s", &FrictionIdentificationResult::simulated_s)
      .def_readonly("wall_s", &FrictionIdentificationResult::wall_s)
      .def_readonly("files", &FrictionIdentificationResult::files)
      .def("worst_relative_error", &FrictionIdentificationResult::worst_relative_error,
           "Largest |relative error| over the identified Coulomb, viscous and static values.");
  m.def("identify_friction", [](const O& o, bool progress) {
        return run_released<FrictionIdentificationResult>(o, progress, [](const O& x, std::ostream* s) { return identify_friction(x, s); });
      }, py::arg("options"), py::arg("progress") = true, "Runs the friction identification (GIL released).");
  m.def("friction_identification_table", &friction_identification_table, py::arg("result"), "The markdown table.");
  m.def("run_friction_identification_command", [](const O& o) {
        return run_released<int>(o, true, [](const O& x, std::ostream* s) { return run_friction_identification_command(x, *s); });
      }, py::arg("options"), "`phri identify-friction`: run, write the files and figure, print the table. Returns 0.");
}

void bind_tracking_types(py::module_& m) {
  py::enum_<TrackingScenario>(m, "TrackingScenario")
      .value("static", TrackingScenario::kStatic)
      .value("dynamic", TrackingScenario::kDynamic);
  py::enum_<PayloadMode>(m, "PayloadMode")
      .value("tool_mass", PayloadMode::kToolMass)
      .value("hung_after_switch", PayloadMode::kHungAfterSwitch);
  using R = TorqueTrackingRun;
  py::class_<R>(m, "TorqueTrackingRun", "Statistics of ||tau_d - tau_s|| of one scenario x loop.")
      .def_readonly("scenario", &R::scenario)
      .def_readonly("loop", &R::loop)
      .def_readonly("rms_Nm", &R::rms_Nm)
      .def_readonly("p95_Nm", &R::p95_Nm)
      .def_readonly("max_Nm", &R::max_Nm)
      .def_readonly("bias_Nm", &R::bias_Nm)
      .def_readonly("rms_true_Nm", &R::rms_true_Nm)
      .def_readonly("ee_position_rms_mm", &R::ee_position_rms_mm)
      .def_readonly("samples", &R::samples)
      .def_readonly("qp_fallbacks", &R::qp_fallbacks)
      .def_readonly("csv_path", &R::csv_path);
  py::class_<TorqueTrackingResult>(m, "TorqueTrackingResult", "Every scenario x loop run and the files written.")
      .def_readonly("runs", &TorqueTrackingResult::runs)
      .def_readonly("simulated_s", &TorqueTrackingResult::simulated_s)
      .def_readonly("wall_s", &TorqueTrackingResult::wall_s)
      .def_readonly("files", &TorqueTrackingResult::files)
      .def("rms_ratio", &TorqueTrackingResult::rms_ratio, py::arg("scenario"), "High-velocity RMS / custom RMS.");
}

TorqueTrackingOptions located_tracking_options() {
  using O = TorqueTrackingOptions;
  return located(O{}, {&O::plant_config_path, &O::urdf_path, &O::actuators_path, &O::collision_path, &O::figure_script});
}

void bind_tracking(py::module_& m) {
  bind_tracking_types(m);
  using O = TorqueTrackingOptions;
  py::class_<O>(m, "TorqueTrackingOptions", "`phri experiment torque-tracking`: custom vs Kinova high-velocity loop.")
      .def(py::init(&located_tracking_options))
      .def_readwrite("plant_config_path", &O::plant_config_path)
      .def_readwrite("urdf_path", &O::urdf_path)
      .def_readwrite("actuators_path", &O::actuators_path)
      .def_readwrite("collision_path", &O::collision_path)
      .def_readwrite("output_dir", &O::output_dir, "Empty: no files.")
      .def_readwrite("figure_script", &O::figure_script, "Empty: no figure.")
      .def_readwrite("seed", &O::seed)
      .def_readwrite("model_mismatch", &O::model_mismatch)
      .def_readwrite("scenarios", &O::scenarios)
      .def_readwrite("loops", &O::loops)
      .def_readwrite("position_phase_s", &O::position_phase_s)
      .def_readwrite("static_duration_s", &O::static_duration_s)
      .def_readwrite("dynamic_duration_s", &O::dynamic_duration_s)
      .def_readwrite("transient_s", &O::transient_s)
      .def_readwrite("payload_kg", &O::payload_kg)
      .def_readwrite("payload_mode", &O::payload_mode)
      .def_readwrite("static_external_torque", &O::static_external_torque)
      .def_readwrite("custom_torque", &O::custom_torque)
      .def_readwrite("torque_constant_error", &O::torque_constant_error, "< 0: the plant file's value.")
      .def_readwrite("mismatch_seed", &O::mismatch_seed, "None: the plant file's mismatch.seed.");
  m.def("run_torque_tracking", [](const O& o, bool progress) {
        return run_released<TorqueTrackingResult>(o, progress, [](const O& x, std::ostream* s) { return run_torque_tracking(x, s); });
      }, py::arg("options"), py::arg("progress") = true, "Runs every scenario x loop of the options (GIL released).");
  m.def("torque_tracking_table", &torque_tracking_table, py::arg("result"), py::arg("options"), "The markdown table.");
  m.def("run_torque_tracking_command", [](const O& o) {
        return run_released<int>(o, true, [](const O& x, std::ostream* s) { return run_torque_tracking_command(x, *s); });
      }, py::arg("options"), "`phri experiment torque-tracking`: run, write the files and figure, print the table.");
  using S = StaticSweepOptions;
  py::class_<S>(m, "StaticSweepOptions", "`phri experiment torque-tracking --static-sweep`.")
      .def(py::init([] {
        S s;
        s.tracking = located_tracking_options();
        s.figure_script = locate(s.figure_script);
        return s;
      }))
      .def_readwrite("tracking", &S::tracking)
      .def_readwrite("torque_constant_errors", &S::torque_constant_errors)
      .def_readwrite("mismatch_seeds", &S::mismatch_seeds)
      .def_readwrite("output_dir", &S::output_dir)
      .def_readwrite("figure_script", &S::figure_script);
  m.def("run_static_sweep_command", [](const S& o) {
        return run_released<int>(o, true, [](const S& x, std::ostream* s) { return run_static_sweep_command(x, *s); });
      }, py::arg("options"), "The static scenario at several drive-gain errors x mismatch seeds; prints the table.");
}

void bind_safety_fuzz(py::module_& m) {
  py::enum_<FaultSet>(m, "FaultSet").value("none", FaultSet::kNone).value("subset", FaultSet::kSubset).value("all", FaultSet::kAll);
  using O = SafetyFuzzOptions;
  py::class_<O>(m, "SafetyFuzzOptions", "`phri experiment safety-fuzz`: seeded pushes and sensor faults.")
      .def(py::init([] {
        return located(O{}, {&O::plant_config_path, &O::urdf_path, &O::actuators_path, &O::collision_path, &O::figure_script});
      }))
      .def_readwrite("plant_config_path", &O::plant_config_path)
      .def_readwrite("output_dir", &O::output_dir, "Empty: no files.")
      .def_readwrite("figure_script", &O::figure_script, "Empty: no figure.")
      .def_readwrite("seed", &O::seed)
      .def_readwrite("pushes", &O::pushes)
      .def_readwrite("pushes_per_run", &O::pushes_per_run)
      .def_readwrite("targeted_pushes", &O::targeted_pushes)
      .def_readwrite("faults", &O::faults)
      .def_readwrite("modes", &O::modes)
      .def_readwrite("loops", &O::loops)
      .def_readwrite("jobs", &O::jobs)
      .def_readwrite("replay", &O::replay);
  py::class_<SafetyFuzzResult>(m, "SafetyFuzzResult", "Windows judged, runs, times and the files written.")
      .def_readonly("runs", &SafetyFuzzResult::runs)
      .def_readonly("simulated_s", &SafetyFuzzResult::simulated_s)
      .def_readonly("wall_s", &SafetyFuzzResult::wall_s)
      .def_readonly("files", &SafetyFuzzResult::files)
      .def_property_readonly("records", [](const SafetyFuzzResult& r) { return r.records.size(); }, "Number of windows judged.")
      .def("controller_failures", &SafetyFuzzResult::controller_failures, "Windows failed by the controller (not the operator).")
      .def("pushes", &SafetyFuzzResult::pushes, "Push windows (random and targeted).")
      .def("faults", &SafetyFuzzResult::faults, "Sensor-fault windows.");
  m.def("run_safety_fuzz", [](const O& o, bool progress) {
        return run_released<SafetyFuzzResult>(o, progress, [](const O& x, std::ostream* s) { return run_safety_fuzz(x, s); });
      }, py::arg("options"), py::arg("progress") = true, "Runs the fuzz (GIL released; `jobs` threads).");
  m.def("run_safety_fuzz_command", [](const O& o, bool fail_on_violation) {
        return run_released<int>(o, true, [fail_on_violation](const O& x, std::ostream* s) {
          return run_safety_fuzz_command(x, fail_on_violation, *s);
        });
      }, py::arg("options"), py::arg("fail_on_violation") = false, "`phri experiment safety-fuzz`; returns its exit status.");
}

void bind_drop_test(py::module_& m) {
  py::enum_<DropMode>(m, "DropMode", "Drop-test mode.").value("torque", DropMode::kTorque).value("position", DropMode::kPosition);
  py::class_<DropRun>(m, "DropRun", "Metrics of one drop (e_z after the catch).")
      .def_readonly("mode", &DropRun::mode)
      .def_readonly("index", &DropRun::index)
      .def_readonly("seed", &DropRun::seed)
      .def_readonly("catch_s", &DropRun::catch_s)
      .def_readonly("peak_mm", &DropRun::peak_mm)
      .def_readonly("stabilisation_s", &DropRun::stabilisation_s)
      .def_readonly("residual_mm", &DropRun::residual_mm)
      .def_readonly("censored", &DropRun::censored)
      .def_readonly("residual_shift_mm", &DropRun::residual_shift_mm)
      .def_readonly("qp_fallbacks", &DropRun::qp_fallbacks)
      .def_readonly("safe_stop", &DropRun::safe_stop)
      .def_readonly("loop_ran", &DropRun::loop_ran)
      .def("invalid_reason", &DropRun::invalid_reason, "Empty: valid.")
      .def_readonly("error_mm", &DropRun::error_mm, "e_z over the window, one sample per period (a copy).");
  py::class_<DropTestResult>(m, "DropTestResult", "Every drop, torque mode first, and the files written.")
      .def_readonly("runs", &DropTestResult::runs)
      .def_readonly("simulated_s", &DropTestResult::simulated_s)
      .def_readonly("wall_s", &DropTestResult::wall_s)
      .def_readonly("files", &DropTestResult::files);
  using O = DropTestOptions;
  py::class_<O>(m, "DropTestOptions", "`phri experiment drop-test`: torque vs position mode, 30 + 30 drops.")
      .def(py::init([] {
        return located(O{}, {&O::plant_config_path, &O::urdf_path, &O::actuators_path, &O::collision_path, &O::figure_script});
      }))
      .def_readwrite("output_dir", &O::output_dir, "Empty: no files.")
      .def_readwrite("figure_script", &O::figure_script, "Empty: no figure.")
      .def_readwrite("drops", &O::drops)
      .def_readwrite("jobs", &O::jobs)
      .def_readwrite("first_seed", &O::first_seed)
      .def_readwrite("release_s", &O::release_s)
      .def_readwrite("window_s", &O::window_s)
      .def_readwrite("observer_gain", &O::observer_gain)
      .def_readwrite("external_torque_source", &O::external_torque_source)
      .def_readwrite("held_by_hand", &O::held_by_hand)
      .def_readwrite("cable_damping_Ns_per_m", &O::cable_damping_Ns_per_m, "None: the plant file's.");
  m.def("run_drop_test", [](const O& o, bool progress) {
        return run_released<DropTestResult>(o, progress, [](const O& x, std::ostream* s) { return run_drop_test(x, s); });
      }, py::arg("options"), py::arg("progress") = true, "Runs the drops (threads, GIL released).");
}

}  // namespace

void bind_experiments(py::module_& m) {
  bind_drop_test(m);
  bind_friction(m);
  bind_tracking(m);
  bind_safety_fuzz(m);
}

}  // namespace phri::python
