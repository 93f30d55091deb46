#include <phri/experiments/evaluation.hpp>

#include <phri/core/format.hpp>
#include <phri/experiments/drop_test.hpp>
#include <phri/experiments/dual_compliance.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/torque_tracking.hpp>

#include <algorithm>
#include <chrono>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

std::string in_root(const EvaluationOptions& o, const std::string& relative) {
  return o.root.empty() || o.root == "." ? relative : o.root + "/" + relative;
}

// Each evaluation prints its own progress, indented under a header; its table goes to the report.
class Section {
public:
  Section(std::ostream& out, const char* name) : out_(out), start_(std::chrono::steady_clock::now()) {
    out_ << "== " << name << std::endl;
  }
  ~Section() {
    out_ << "   (" << format_fixed(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(), 1)
         << " s)" << std::endl;
  }

private:
  std::ostream& out_;
  std::chrono::steady_clock::time_point start_;
};

void friction(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "friction identification");
  FrictionIdentificationOptions f;
  f.plant_config_path = in_root(o, f.plant_config_path);
  f.urdf_path = in_root(o, f.urdf_path);
  f.figure_script = in_root(o, f.figure_script);
  f.output_dir = output_path(o.output_dir, "friction_identification");
  if (o.quick) f.joints = {1, 5};  // one large and one small actuator
  run_friction_identification_command(f, out);
  // Issue 39: the same protocol on a plant whose friction differs in form from the model (Stribeck
  // curve + position ripple), kept to a few seconds: one small joint, its v_s sweep with 6 levels per
  // direction. `phri identify-friction --plant-friction stribeck-ripple` is the full run.
  out << "-- plant friction of another form (Stribeck + ripple)" << std::endl;
  FrictionIdentificationOptions g = f;
  g.plant_friction = PlantFrictionForm::kStribeckRipple;
  g.joints = {5};
  g.stribeck_ripple.sweep_joints = {5};
  g.stribeck_ripple.sweep_speed_levels = 6;
  g.output_dir = output_path(o.output_dir, "friction_form");
  g.figure_script.clear();
  const FrictionIdentificationResult r = identify_friction(g, nullptr);
  out << model_form_markdown(r) << "\n" << sweep_markdown(r.sweep);
}

TorqueTrackingOptions tracking_files(const EvaluationOptions& o, const char* folder) {
  TorqueTrackingOptions t;
  for (std::string* path : {&t.plant_config_path, &t.urdf_path, &t.actuators_path, &t.collision_path, &t.figure_script}) {
    *path = in_root(o, *path);
  }
  t.output_dir = output_path(o.output_dir, folder);
  return t;
}

void torque_tracking(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "torque tracking (static and dynamic)");
  TorqueTrackingOptions t = tracking_files(o, "torque_tracking");
  if (o.quick) {
    t.static_duration_s = 2.0;
    t.dynamic_duration_s = 4.0;
  }
  run_torque_tracking_command(t, out);
  // Issue 15: the static comparison again on the elastic plant (the spring between the drive and
  // the sensor is what the custom loop's filter H(z) was designed against).
  out << "-- static scenario, elastic joints" << std::endl;
  TorqueTrackingOptions e = tracking_files(o, "torque_tracking_elastic");
  e.scenarios = {TrackingScenario::kStatic};
  e.elastic = true;
  e.figure_script.clear();
  if (o.quick) e.static_duration_s = 2.0;
  const TorqueTrackingResult r = run_torque_tracking(e, nullptr);
  out << torque_tracking_table(r, e);
}

// The dynamic scenario with the four low-level loops of the paper's Fig. dynamic-comparison.
void dynamic_tracking(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "dynamic tracking (position, custom, Kinova torque, Kinova high-velocity)");
  TorqueTrackingOptions t = dynamic_tracking_options();
  for (std::string* path : {&t.plant_config_path, &t.urdf_path, &t.actuators_path, &t.collision_path}) *path = in_root(o, *path);
  t.output_dir = output_path(o.output_dir, "dynamic_tracking");
  if (o.quick) t.dynamic_duration_s = 4.0;
  run_torque_tracking_command(t, out);
}

DropTestOptions drop_files(const EvaluationOptions& o, const std::string& folder) {
  DropTestOptions d;
  for (std::string* path : {&d.plant_config_path, &d.urdf_path, &d.actuators_path, &d.collision_path, &d.figure_script}) {
    *path = in_root(o, *path);
  }
  d.output_dir = output_path(o.output_dir, folder);
  d.jobs = o.jobs;
  d.drops = o.quick ? 4 : o.drops;
  if (o.quick) {
    d.release_s = 2.0;
    d.window_s = 3.0;
  }
  return d;
}

void drop_test(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "drop test (torque vs position)");
  run_drop_test_command(drop_files(o, "drop_test"), out);
}

// The drop test with one setting changed at a time: which physical effect decides the comparison.
void sensitivity(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "drop-test sensitivity");
  struct Variant {
    const char* name;
    void (*apply)(DropTestOptions&);
  };
  const Variant variants[] = {
      {"observer_only_K10", [](DropTestOptions& d) { d.external_torque_source = ExternalTorqueSource::kObserver; }},
      {"observer_only_K50",
       [](DropTestOptions& d) {
         d.external_torque_source = ExternalTorqueSource::kObserver;
         d.observer_gain = 50.0;
       }},
      {"ft_only", [](DropTestOptions& d) { d.external_torque_source = ExternalTorqueSource::kForceTorqueSensor; }},
      {"cable_damping_50", [](DropTestOptions& d) { d.cable_damping_Ns_per_m = 50.0; }},
      // The cable's stiffness has no source (the plant file's 2000 N/m is an estimate); the reference's
      // computed table (reference/kinova_gen3_dynamics.md, paracord EA ~ break / 0.30) gives 32620 N/m
      // for 25 cm. Damping ratio kept at the main setting's 0.1: b = 2 0.1 sqrt(k 1.25 kg).
      {"cable_stiffness_8000",
       [](DropTestOptions& d) {
         d.cable_stiffness_N_per_m = 8000.0;
         d.cable_damping_Ns_per_m = 20.0;
       }},
      {"cable_stiffness_32620",
       [](DropTestOptions& d) {
         d.cable_stiffness_N_per_m = 32620.0;
         d.cable_damping_Ns_per_m = 40.4;
       }},
      {"vendor_gains_x0.5", [](DropTestOptions& d) { d.vendor_gain_scale = 0.5; }},
      {"no_release_spread", [](DropTestOptions& d) { d.release_spread_scale = 0.0; }},
      {"weight_latched_on_tool", [](DropTestOptions& d) { d.held_by_hand = false; }},
      {"rigid_joints", [](DropTestOptions& d) { d.elastic = false; }},
      {"servo_on_link_encoder", [](DropTestOptions& d) { d.servo_encoder = SimRobotConfig::Elasticity::Encoder::kLink; }},
      {"soft_joints_4000_3500",
       [](DropTestOptions& d) { d.joint_stiffness_Nm_per_rad = std::vector<double>{4000, 4000, 4000, 4000, 3500, 3500, 3500}; }},
      {"position_qp_on_measured_state", [](DropTestOptions& d) { d.position_open_loop = false; }},
  };
  for (const Variant& v : variants) {
    DropTestOptions d = drop_files(o, std::string("sensitivity/") + v.name);
    d.drops = o.sensitivity_drops;
    d.release_s = std::min(d.release_s, 3.0);  // 2 s of torque control before the drop settle the arm
    d.figure_script.clear();
    v.apply(d);
    out << "-- " << v.name << std::endl;
    const DropTestResult r = run_drop_test(d, nullptr);
    out << drop_test_table(r, d);
  }
}

void dual_compliance(const EvaluationOptions& o, std::ostream& out) {
  const Section section(out, "dual compliance");
  DualComplianceOptions d;
  for (std::string* path : {&d.plant_config_path, &d.urdf_path, &d.actuators_path, &d.collision_path}) *path = in_root(o, *path);
  d.output_dir = output_path(o.output_dir, "dual_compliance");
  run_dual_compliance_command(d, out);
}

}  // namespace

TorqueTrackingOptions dynamic_tracking_options() {
  TorqueTrackingOptions t;
  t.scenarios = {TrackingScenario::kDynamic};
  t.loops = {LowLevelMode::kPosition, LowLevelMode::kCurrent, LowLevelMode::kKinovaTorque,
             LowLevelMode::kKinovaTorqueHighVelocity};
  t.output_dir = "results/dynamic_tracking";
  t.figure_script.clear();  // the evaluation report draws the y/z errors
  return t;
}

int run_evaluation_command(const EvaluationOptions& o, std::ostream& out) {
  const auto start = std::chrono::steady_clock::now();
  ensure_output_directory(o.output_dir);
  out << "phri evaluate: " << (o.quick ? "quick protocol" : "the paper's protocol") << ", " << o.jobs << " jobs, into "
      << o.output_dir << std::endl;
  friction(o, out);
  torque_tracking(o, out);
  drop_test(o, out);
  if (!o.quick) sensitivity(o, out);
  dynamic_tracking(o, out);
  dual_compliance(o, out);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out << "== report" << std::endl;
  // The report lists every parameter of the files the evaluations read, with its source.
  const bool ok = run_figure_script(in_root(o, o.report_script),
                                    {o.output_dir, o.quick ? "quick" : "full", format_fixed(seconds, 1),
                                     in_root(o, "configs/plant_gen3.yaml"), in_root(o, "robots/kinova_gen3/actuators.yaml")},
                                    out);
  out << (ok ? "wrote " + output_path(o.output_dir, "report.md") + " and " + output_path(o.output_dir, "report.html")
             : std::string("the report script failed"))
      << std::endl;
  return ok ? 0 : 1;
}

}  // namespace phri
