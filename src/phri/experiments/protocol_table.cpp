#include <phri/experiments/protocol_table.hpp>

#include <phri/core/format.hpp>
#include <phri/experiments/drop_test.hpp>
#include <phri/experiments/dual_compliance.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/torque_tracking.hpp>

#include <algorithm>
#include <string_view>

namespace phri {
namespace {

// The reference notes' transcriptions of the paper and its code (the project never reads them at run
// time; the rows name them so that a reader can check).
constexpr const char* kPaperDrop = "[PAPER] section 'Stiffness in static configurations'";
constexpr const char* kDemoSin = "[DEMO] the paper's demo, 'Sin' state (reference paper_parameters.md section 5)";
constexpr const char* kDemoPosture = "[DEMO] the paper's demo postureTarget";
constexpr const char* kSetting = "setting (not a physical value)";

std::string number(double value, const char* unit) { return format_general(value, 6) + (*unit ? " " : "") + unit; }

std::string list(const std::vector<double>& values, const char* unit) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + format_general(values[i], 6);
  return text + "]" + (*unit ? " " : "") + unit;
}

std::string joints_text(const std::vector<int>& joints) {
  std::string text;
  for (std::size_t i = 0; i < joints.size(); ++i) text += (i ? ", " : "") + std::to_string(joints[i]);
  return text;
}

std::string yes_no(bool value) { return value ? "yes" : "no"; }

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

bool runs(const TorqueTrackingOptions& o, TrackingScenario s) {
  return std::find(o.scenarios.begin(), o.scenarios.end(), s) != o.scenarios.end();
}

}  // namespace

void ProtocolTable::add(const std::string& experiment, const std::string& parameter, const std::string& value,
                        const std::string& source) {
  rows_.push_back({experiment, parameter, value, source});
}

std::string ProtocolTable::csv() const {
  std::string text = "experiment,parameter,value,source\n";
  for (const ProtocolParameter& r : rows_) {
    text += quoted(r.experiment) + ',' + quoted(r.parameter) + ',' + quoted(r.value) + ',' + quoted(r.source) + '\n';
  }
  return text;
}

void ProtocolTable::add_friction_identification(const std::string& e, const FrictionIdentificationOptions& o) {
  add(e, "joints", joints_text(o.joints), "[PAPER] section 'Friction parameters identification': each joint");
  add(e, "plant friction off the model", number(100.0 * o.friction_perturbation, "% at most per coefficient"),
      "no source (the identification must find a friction it was not given)");
  add(e, "plant friction form", o.plant_friction == PlantFrictionForm::kModelForm ? "the model's" : "Stribeck + ripple",
      o.plant_friction == PlantFrictionForm::kModelForm ? kSetting : "issue 39: a form the model does not have");
  add(e, "speed levels per direction", std::to_string(o.speed_levels),
      "no source ([PAPER]: constant currents on each joint, their number not given)");
  add(e, "slowest level", number(o.min_speed_rad_s, "rad/s"), "no source");
  add(e, "fastest level", number(100.0 * o.max_speed_fraction, "% of the joint's speed limit"), "no source");
  add(e, "run-up, settle, average", number(o.run_up_s, "") + " / " + number(o.settle_s, "") + " / " + number(o.average_s, "s"),
      "no source");
  add(e, "static friction search", o.static_search ? std::to_string(o.static_bisection_steps) + " bisection steps of " +
                                                          number(o.static_trial_s, "s") + " per direction"
                                                    : "off",
      "no source ([PAPER] adds 'a potential estimation of the static friction')");
  add(e, "breakaway motion", number(o.breakaway_rad, "rad"), "no source");
  add(e, "seed", std::to_string(o.seed), kSetting);
}

void ProtocolTable::add_torque_tracking(const std::string& e, const TorqueTrackingOptions& o) {
  std::string loops;
  for (LowLevelMode m : o.loops) loops += (loops.empty() ? "" : ", ") + std::string(to_string(m));
  add(e, "loops", loops, "[PAPER] figures torque-tracking and dynamic-comparison");
  add(e, "start posture", list(o.start_q_rad, "rad"), kDemoPosture);
  add(e, "position control before the switch", number(o.position_phase_s, "s"),
      "[PAPER]: 'in position control and then switching'; its length: no source");
  add(e, "transient left out after the switch", number(o.transient_s, "s"), "no source");
  add(e, "joint elasticity", yes_no(o.elastic), "issue 39: one elastic plant for every evaluation");
  add(e, "position mode open loop", yes_no(o.position_open_loop), "[DEMO] mc_rtc integrates its own state");
  add(e, "plant link inertials off the model", o.model_mismatch ? "up to 5 %" : "no",
      "no source (a model is never exact)");
  if (runs(o, TrackingScenario::kStatic)) {
    add(e, "static: duration after the switch", number(o.static_duration_s, "s"), "no source");
    add(e, "static: payload", number(o.payload_kg, "kg") +
                                  (o.payload_mode == PayloadMode::kToolMass ? " on the tool from the start" : " hung after the switch"),
        "[PAPER]: 'we attached a weight'; its mass: the drop test's 1.25 kg");
    add(e, "static: compliance", std::string(to_string(o.static_compliance)), "[PAPER] a stiff pose task");
    add(e, "static: external torque", std::string(to_string(o.static_external_torque)), "no source");
  }
  if (runs(o, TrackingScenario::kDynamic)) {
    add(e, "dynamic: duration after the switch", number(o.dynamic_duration_s, "s"), "no source (two triangle periods)");
    add(e, "dynamic: z sine amplitude, frequency", number(o.sine_amplitude_m, "m") + ", " + number(o.sine_omega_rad_s, "rad/s"),
        kDemoSin);
    add(e, "dynamic: y triangle speed, range",
        number(o.triangle_speed_m_s, "m/s") + ", [" + number(o.triangle_min_m, "") + ", " + number(o.triangle_max_m, "m]"),
        kDemoSin);
    add(e, "dynamic: trajectory delay, sine fade-in", number(o.trajectory_delay_s, "") + " / " + number(o.fade_in_s, "s"),
        "no source (the demo starts at full speed)");
    add(e, "dynamic: compliance", std::string(to_string(o.dynamic_compliance)), "[DEMO] 'Sin' state, null-space compliance");
  }
  add(e, "seed", std::to_string(o.seed), kSetting);
}

void ProtocolTable::add_drop_test(const std::string& e, const DropTestOptions& o) {
  add(e, "drops per mode", std::to_string(o.drops), std::string(kPaperDrop) + ": 30 drops");
  add(e, "start posture", list(o.start_q_rad, "rad"), std::string(kDemoPosture) + " (the paper: 'extended horizontally')");
  add(e, "torque mode: loop, compliance",
      std::string(to_string(o.torque_loop)) + ", " + std::string(to_string(o.torque_compliance)),
      std::string(kPaperDrop) + ": stiff pose task, null-space compliance");
  add(e, "torque mode: external torque, observer gain",
      std::string(to_string(o.external_torque_source)) + ", K_O " + number(o.observer_gain, "1/s"),
      "[DEMO] use_force_sensor and EF_Estimator::setGain (reference paper_parameters.md sections 1.6 and 4)");
  add(e, "position mode open loop", yes_no(o.position_open_loop), "[DEMO] mc_rtc integrates its own state");
  add(e, "position control before the switch", number(o.switch_s, "s"), "no source (the F/T bias settles)");
  add(e, "release", number(o.release_s, "s after the start"), "issue 15's protocol; its time: no source");
  add(e, "weight", o.held_by_hand ? "held by a hand until released" : "latched on the tool",
      "issue 15's protocol (the paper: 'attaching a 1.25kg weight ... and letting it drop')");
  add(e, "window after the catch", number(o.window_s, "s"), "no source (the paper's settling times are below 1 s)");
  add(e, "residual: mean over the window's last", number(o.residual_window_s, "s"), "no source");
  add(e, "error before the drop: mean over", number(o.pre_release_s, "s"), "no source");
  add(e, "stabilisation bands", list(o.stabilisation_bands_mm, "mm"),
      "no source (the paper does not state its criterion; every band is shown)");
  add(e, "joint elasticity", yes_no(o.elastic), "issue 39: one elastic plant for every evaluation");
  add(e, "plant link inertials and drive gains off the model", o.model_mismatch ? "up to 5 %" : "no",
      "no source (a model is never exact)");
  add(e, "first seed", std::to_string(o.first_seed), kSetting);
}

void ProtocolTable::add_dual_compliance(const std::string& e, const DualComplianceOptions& o) {
  add(e, "start posture", list(o.start_q_rad, "rad"), kDemoPosture);
  add(e, "position control before the switch", number(o.switch_s, "s"), "no source (the F/T bias settles)");
  for (std::size_t i = 0; i < o.guides.size(); ++i) {
    const DualComplianceOptions::Guide& g = o.guides[i];
    add(e, "guide " + std::to_string(i + 1),
        list({g.force_N.x(), g.force_N.y(), g.force_N.z()}, "N") + " from " + number(g.start_s, "s") + " for " +
            number(g.duration_s, "s") + " (half sine)",
        "ESTIMATE: a hand guiding a tool by about 10 cm, above the 8 N touch threshold");
  }
  add(e, "drift measured over", number(o.drift_window_s, "s"), "no source");
  add(e, "duration", number(o.duration_s, "s"), "no source");
  add(e, "seed", std::to_string(o.seed), kSetting);
}

}  // namespace phri
