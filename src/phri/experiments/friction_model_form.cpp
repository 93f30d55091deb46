#include <phri/experiments/friction_model_form.hpp>

#include <phri/config/sim_robot_config.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/friction_identification.hpp>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <sstream>
#include <utility>

namespace phri {
namespace {

constexpr int kGridPoints = 400;         // per speed band, geometric
constexpr double kLargeErrorFraction = 0.1;  // of the static level: "the model cannot fit here"

double sign(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

double model_friction(const JointFrictionEstimate& e, double v) {
  return e.identified.coulomb_Nm * sign(v) + e.identified.viscous_Nms_per_rad * v;
}

struct BandError {
  double rms = 0.0, max = 0.0, max_at = 0.0;
};

// model - truth on a geometric grid of positive speeds (both are odd in v: the negative side mirrors it).
BandError band_error(const JointFrictionEstimate& e, const StickSlipFriction::Parameters& dry, double from, double to) {
  BandError b;
  if (!(to > from && from > 0.0)) return b;
  double sum2 = 0.0;
  for (int k = 0; k < kGridPoints; ++k) {
    const double v = from * std::pow(to / from, static_cast<double>(k) / (kGridPoints - 1));
    const double err = model_friction(e, v) - mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, v);
    sum2 += err * err;
    if (std::abs(err) > b.max) {
      b.max = std::abs(err);
      b.max_at = v;
    }
  }
  b.rms = std::sqrt(sum2 / kGridPoints);
  return b;
}

// The largest speed in [from, to] where |model - truth| exceeds the fraction of the static level (0: none).
double large_error_below(const JointFrictionEstimate& e, const StickSlipFriction::Parameters& dry, double from, double to) {
  double below = 0.0;
  for (int k = 0; k < kGridPoints; ++k) {
    const double v = from * std::pow(to / from, static_cast<double>(k) / (kGridPoints - 1));
    const double err = model_friction(e, v) - mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, v);
    if (std::abs(err) > kLargeErrorFraction * e.plant.static_Nm) below = v;
  }
  return below;
}

// The largest speed in [from, to] where the plant's mean curve falls with speed (0: none).
double negative_slope_below(const JointFrictionEstimate& e, const StickSlipFriction::Parameters& dry, double from, double to) {
  double below = 0.0;
  double previous = mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, from);
  for (int k = 1; k < kGridPoints; ++k) {
    const double v = from * std::pow(to / from, static_cast<double>(k) / (kGridPoints - 1));
    const double g = mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, v);
    if (g < previous) below = v;
    previous = g;
  }
  return below;
}

std::string pct_of(double x, double of) { return format_fixed(of != 0.0 ? 100.0 * x / of : 0.0, 1) + " %"; }

void form_csv_fields(std::ostream& s, const ModelFormError& f) {
  for (double x : {f.stribeck_velocity_rad_s, f.stribeck_exponent, f.ripple_Nm, f.breakaway_velocity_rad_s, f.slowest_level_rad_s,
                   f.fastest_level_rad_s, f.rms_levels_Nm, f.max_levels_Nm, f.max_levels_at_rad_s, f.rms_low_Nm, f.max_low_Nm,
                   f.error_at_breakaway_Nm, f.ten_percent_below_rad_s, f.level_scatter_rms_Nm, f.level_scatter_max_Nm}) {
    s << ',' << format_fixed(x, 6);
  }
  s << ',' << f.unsteady_levels << ',' << format_fixed(f.fastest_unsteady_target_rad_s, 6) << ','
    << format_fixed(f.negative_slope_below_rad_s, 6);
}

constexpr const char* kFormCsvFields =
    "stribeck_velocity_rad_s,stribeck_exponent,ripple_Nm,breakaway_velocity_rad_s,slowest_level_rad_s,fastest_level_rad_s,"
    "rms_levels_Nm,max_levels_Nm,max_levels_at_rad_s,rms_low_Nm,max_low_Nm,error_at_breakaway_Nm,ten_percent_below_rad_s,"
    "level_scatter_rms_Nm,level_scatter_max_Nm,unsteady_levels,fastest_unsteady_target_rad_s,negative_slope_below_rad_s";

// Where the identified Coulomb level lies against the plant's Coulomb and static levels.
std::string coulomb_placement(double identified, double coulomb, double stat) {
  if (identified < coulomb) return "below the plant's Coulomb level";
  if (identified > stat) return "above the plant's static level";
  return "between the plant's Coulomb and static levels (" + format_fixed(100.0 * (identified - coulomb) / (stat - coulomb), 0) +
         " % of the way up)";
}

// The sentences of one valid joint, every number from the run.
void joint_sentences(std::ostream& s, const JointFrictionEstimate& e) {
  const ModelFormError& f = e.form;
  const double ts = e.plant.static_Nm;
  s << "- Joint " << e.joint << ": identified Coulomb " << format_fixed(e.identified.coulomb_Nm, 3) << " N.m, "
    << coulomb_placement(e.identified.coulomb_Nm, e.plant.coulomb_Nm, ts) << " (" << format_fixed(e.plant.coulomb_Nm, 3) << " / "
    << format_fixed(ts, 3) << " N.m). Over the levels' speeds (" << format_fixed(f.slowest_level_rad_s, 3) << "-"
    << format_fixed(f.fastest_level_rad_s, 3) << " rad/s) the model is off the plant's mean curve by "
    << format_fixed(f.rms_levels_Nm, 3) << " N.m RMS (" << pct_of(f.rms_levels_Nm, ts) << " of static), at most "
    << format_fixed(f.max_levels_Nm, 3) << " N.m (" << pct_of(f.max_levels_Nm, ts) << ") at " << format_fixed(f.max_levels_at_rad_s, 3)
    << " rad/s; below the slowest level, down to the breakaway speed " << format_fixed(f.breakaway_velocity_rad_s, 4)
    << " rad/s, by up to " << format_fixed(f.max_low_Nm, 3) << " N.m (" << pct_of(f.max_low_Nm, ts) << "). At the breakaway speed "
    << "the model's sign step gives " << format_fixed(e.identified.coulomb_Nm, 3) << " N.m, "
    << format_fixed(f.error_at_breakaway_Nm, 3) << " N.m off the curve (" << pct_of(std::abs(f.error_at_breakaway_Nm), ts) << ").";
  if (f.ten_percent_below_rad_s > 0.0) {
    s << " The model is off by more than " << format_fixed(100.0 * kLargeErrorFraction, 0) << " % of the static level below "
      << format_fixed(f.ten_percent_below_rad_s, 4) << " rad/s.";
  } else {
    s << " Nowhere from the breakaway speed to the fastest level is it off by more than " << format_fixed(100.0 * kLargeErrorFraction, 0)
      << " % of the static level.";
  }
  s << " The steady levels scatter about the plant's mean curve by " << format_fixed(f.level_scatter_rms_Nm, 3) << " N.m RMS, at most "
    << format_fixed(f.level_scatter_max_Nm, 3) << " N.m (ripple amplitude " << format_fixed(f.ripple_Nm, 3) << " N.m); "
    << f.unsteady_levels << " of " << e.levels_total << " levels were not steady and are not in the fit"
    << (f.unsteady_levels > 0 ? " (run-up speeds up to " + format_fixed(f.fastest_unsteady_target_rad_s, 3) + " rad/s)" : "") << ".";
  if (f.negative_slope_below_rad_s > 0.0) {
    s << " The plant's mean curve falls with speed below " << format_fixed(f.negative_slope_below_rad_s, 3)
      << " rad/s: no constant current holds a speed there, so the protocol cannot sample that part of the curve.";
  }
  if (f.static_here_positive_Nm > 0.0) {
    s << " Static: identified " << format_fixed(e.static_positive_Nm, 3) << " / " << format_fixed(e.static_negative_Nm, 3)
      << " N.m (+/-) against the plant's breakaway level where each search started, " << format_fixed(f.static_here_positive_Nm, 3)
      << " / " << format_fixed(f.static_here_negative_Nm, 3) << " N.m (it varies over " << format_fixed(ts - f.ripple_Nm, 3) << "-"
      << format_fixed(ts + f.ripple_Nm, 3) << " N.m with position).";
  }
  s << "\n";
}

}  // namespace

void apply_stribeck_ripple(const StribeckRippleSettings& s, SimRobotConfig& plant) {
  plant.friction.stribeck_velocity_rad_s = s.stribeck_velocity_rad_s;
  plant.friction.stribeck_exponent = s.stribeck_exponent;
  plant.friction.ripple_fraction = s.ripple_fraction;
  plant.friction.ripple_cycles_per_rev = s.ripple_cycles_per_rev;
  // tau_s = ratio tau_c on every joint, on top of whatever overrides (perturbation) set tau_c.
  for (int i = 0; i < plant.actuators.size(); ++i) {
    const std::string& name = plant.actuators[i].joint_name;
    double coulomb = plant.actuators[i].friction.coulomb_Nm;
    for (const SimRobotConfig::ActuatorOverride& o : plant.actuator_overrides) {
      if (o.joint == name && o.coulomb_Nm) coulomb = *o.coulomb_Nm;
    }
    SimRobotConfig::ActuatorOverride o;
    o.joint = name;
    o.coulomb_Nm = coulomb;
    o.static_Nm = s.static_to_coulomb * coulomb;
    plant.actuator_overrides.push_back(o);
  }
}

double mean_sliding_friction(const StickSlipFriction::Parameters& dry, double viscous_Nms_per_rad, double v) {
  StickSlipFriction::Parameters mean = dry;
  mean.ripple_Nm = 0.0;
  return sign(v) * StickSlipFriction::sliding_level(mean, 0.0, std::abs(v)) + viscous_Nms_per_rad * v;
}

ModelFormError model_form_error(const JointFrictionEstimate& e, const std::vector<FrictionLevel>& levels,
                                const StickSlipFriction::Parameters& dry, double q_static_positive, double q_static_negative) {
  ModelFormError f;
  f.computed = true;
  f.stribeck_velocity_rad_s = dry.stribeck_velocity_rad_s;
  f.stribeck_exponent = dry.stribeck_exponent;
  f.ripple_Nm = dry.ripple_Nm;
  f.breakaway_velocity_rad_s = dry.breakaway_velocity_rad_s;
  f.slowest_level_rad_s = 1e9;
  double scatter2 = 0.0;
  int steady = 0;
  for (const FrictionLevel& l : levels) {
    if (!l.steady) {
      ++f.unsteady_levels;
      f.fastest_unsteady_target_rad_s = std::max(f.fastest_unsteady_target_rad_s, l.target_speed_rad_s);
      continue;
    }
    const double v = std::abs(l.velocity_rad_s);
    f.slowest_level_rad_s = std::min(f.slowest_level_rad_s, v);
    f.fastest_level_rad_s = std::max(f.fastest_level_rad_s, v);
    // The level against the truth: the sensor's offset (e's intercept is minus it) plus the mean curve.
    const double d = l.torque_error_Nm - (-e.plant_sensor_offset_Nm + mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, l.velocity_rad_s));
    scatter2 += d * d;
    f.level_scatter_max_Nm = std::max(f.level_scatter_max_Nm, std::abs(d));
    ++steady;
  }
  if (steady == 0) return f;
  f.level_scatter_rms_Nm = std::sqrt(scatter2 / steady);
  const BandError in_levels = band_error(e, dry, f.slowest_level_rad_s, f.fastest_level_rad_s);
  f.rms_levels_Nm = in_levels.rms;
  f.max_levels_Nm = in_levels.max;
  f.max_levels_at_rad_s = in_levels.max_at;
  const BandError low = band_error(e, dry, f.breakaway_velocity_rad_s, f.slowest_level_rad_s);
  f.rms_low_Nm = low.rms;
  f.max_low_Nm = low.max;
  const double vb = f.breakaway_velocity_rad_s;
  f.error_at_breakaway_Nm = model_friction(e, vb) - mean_sliding_friction(dry, e.plant.viscous_Nms_per_rad, vb);
  f.ten_percent_below_rad_s = large_error_below(e, dry, vb, f.fastest_level_rad_s);
  f.negative_slope_below_rad_s = negative_slope_below(e, dry, vb, f.fastest_level_rad_s);
  if (e.static_positive_Nm > 0.0) {
    f.static_here_positive_Nm = StickSlipFriction::breakaway_level(dry, q_static_positive);
    f.static_here_negative_Nm = StickSlipFriction::breakaway_level(dry, q_static_negative);
  }
  return f;
}

namespace {

// One value of one swept parameter: a sliding-only identification of the sweep joints.
void sweep_value(const FrictionIdentificationOptions& o, const char* parameter, double value, std::vector<FrictionFormSweepRow>& rows,
                 std::ostream* progress) {
  FrictionIdentificationOptions sweep = o;
  (std::string(parameter) == "v_s" ? sweep.stribeck_ripple.stribeck_velocity_rad_s : sweep.stribeck_ripple.ripple_fraction) = value;
  sweep.stribeck_ripple.stribeck_velocity_sweep.clear();
  sweep.stribeck_ripple.ripple_fraction_sweep.clear();
  sweep.joints = o.stribeck_ripple.sweep_joints;
  sweep.speed_levels = o.stribeck_ripple.sweep_speed_levels;
  sweep.static_search = false;
  sweep.output_dir.clear();
  sweep.figure_script.clear();
  const FrictionIdentificationResult r = identify_friction(sweep, nullptr);
  for (const JointFrictionEstimate& e : r.joints) {
    FrictionFormSweepRow row;
    row.parameter = parameter;
    row.value = value;
    row.joint = e.joint;
    row.valid = e.valid;
    row.invalid_reason = e.invalid_reason;
    row.coulomb_identified_Nm = e.identified.coulomb_Nm;
    row.coulomb_plant_Nm = e.plant.coulomb_Nm;
    row.static_plant_Nm = e.plant.static_Nm;
    row.viscous_identified_Nms_per_rad = e.identified.viscous_Nms_per_rad;
    row.viscous_plant_Nms_per_rad = e.plant.viscous_Nms_per_rad;
    row.levels_used = e.levels_used;
    row.levels_total = e.levels_total;
    row.error = e.form;
    rows.push_back(row);
    if (progress) {
      *progress << "  sweep " << parameter << " " << format_fixed(value, 3) << ", joint " << e.joint << ": "
                << (e.valid ? "fit RMS error " + format_fixed(e.form.rms_levels_Nm, 3) + " N.m over the levels, " +
                                  format_fixed(e.form.max_low_Nm, 3) + " N.m max below them, " + std::to_string(e.form.unsteady_levels) +
                                  " unsteady levels"
                            : "INVALID (" + e.invalid_reason + ")")
                << std::endl;
    }
  }
}

}  // namespace

std::vector<FrictionFormSweepRow> friction_form_sweeps(const FrictionIdentificationOptions& o, std::ostream* progress) {
  std::vector<FrictionFormSweepRow> rows;
  for (double v_s : o.stribeck_ripple.stribeck_velocity_sweep) sweep_value(o, "v_s", v_s, rows, progress);
  for (double a_r : o.stribeck_ripple.ripple_fraction_sweep) sweep_value(o, "a_r", a_r, rows, progress);
  return rows;
}

std::string model_form_csv(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "joint,name,valid,invalid_reason,plant_coulomb_Nm,plant_static_Nm,plant_viscous_Nms_per_rad,coulomb_Nm,viscous_Nms_per_rad,"
       "static_Nm,static_here_positive_Nm,static_here_negative_Nm,levels_used,levels_total,"
    << kFormCsvFields << '\n';
  for (const JointFrictionEstimate& e : r.joints) {
    s << e.joint << ',' << e.name << ',' << (e.valid ? 1 : 0) << ',' << e.invalid_reason;
    for (double x : {e.plant.coulomb_Nm, e.plant.static_Nm, e.plant.viscous_Nms_per_rad, e.identified.coulomb_Nm,
                     e.identified.viscous_Nms_per_rad, e.identified.static_Nm, e.form.static_here_positive_Nm,
                     e.form.static_here_negative_Nm}) {
      s << ',' << format_fixed(x, 6);
    }
    s << ',' << e.levels_used << ',' << e.levels_total;
    form_csv_fields(s, e.form);
    s << '\n';
  }
  return s.str();
}

std::string sweep_csv(const std::vector<FrictionFormSweepRow>& rows) {
  std::ostringstream s;
  s << "sweep_parameter,sweep_value,joint,valid,invalid_reason,coulomb_Nm,plant_coulomb_Nm,plant_static_Nm,viscous_Nms_per_rad,"
       "plant_viscous_Nms_per_rad,levels_used,levels_total,"
    << kFormCsvFields << '\n';
  for (const FrictionFormSweepRow& r : rows) {
    s << r.parameter << ',' << format_fixed(r.value, 5) << ',' << r.joint << ',' << (r.valid ? 1 : 0) << ',' << r.invalid_reason;
    for (double x : {r.coulomb_identified_Nm, r.coulomb_plant_Nm, r.static_plant_Nm, r.viscous_identified_Nms_per_rad,
                     r.viscous_plant_Nms_per_rad}) {
      s << ',' << format_fixed(x, 6);
    }
    s << ',' << r.levels_used << ',' << r.levels_total;
    form_csv_fields(s, r.error);
    s << '\n';
  }
  return s.str();
}

std::string model_form_markdown(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "Plant friction of another form (Stribeck curve + position-dependent ripple): the identified model against the "
       "plant's true mean sliding friction.\n\n";
  s << "| joint | v_s | Fc plant / static | Fc identified | Fv plant / identified | RMS err, levels' speeds | max err | "
       "max err below the levels | err at breakaway speed | levels' scatter (ripple) | unsteady levels |\n";
  s << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const JointFrictionEstimate& e : r.joints) {
    if (!e.valid) {
      s << "| " << e.joint << " | INVALID: " << e.invalid_reason << " |||||||||\n";
      continue;
    }
    const ModelFormError& f = e.form;
    const double ts = e.plant.static_Nm;
    s << "| " << e.joint << " | " << format_fixed(f.stribeck_velocity_rad_s, 3) << " | " << format_fixed(e.plant.coulomb_Nm, 3) << " / "
      << format_fixed(ts, 3) << " | " << format_fixed(e.identified.coulomb_Nm, 3) << " | " << format_fixed(e.plant.viscous_Nms_per_rad, 3)
      << " / " << format_fixed(e.identified.viscous_Nms_per_rad, 3) << " | " << format_fixed(f.rms_levels_Nm, 3) << " ("
      << pct_of(f.rms_levels_Nm, ts) << ") | " << format_fixed(f.max_levels_Nm, 3) << " (" << pct_of(f.max_levels_Nm, ts) << ") | "
      << format_fixed(f.max_low_Nm, 3) << " (" << pct_of(f.max_low_Nm, ts) << ") | " << format_fixed(f.error_at_breakaway_Nm, 3) << " | "
      << format_fixed(f.level_scatter_rms_Nm, 3) << " rms, " << format_fixed(f.level_scatter_max_Nm, 3) << " max ("
      << format_fixed(f.ripple_Nm, 3) << ") | " << f.unsteady_levels << "/" << e.levels_total << " |\n";
  }
  s << "\nErrors in N.m, model - plant, % of the plant's static level; speeds in rad/s.\n\n";
  for (const JointFrictionEstimate& e : r.joints) {
    if (e.valid) joint_sentences(s, e);
  }
  return s.str();
}

std::string sweep_markdown(const std::vector<FrictionFormSweepRow>& rows) {
  std::ostringstream s;
  s << "Sweeps over the unknowns, one at a time (v_s: Stribeck velocity [rad/s], a_r: ripple amplitude [fraction of "
       "Coulomb]; sliding levels only, no static search):\n\n";
  s << "| parameter | value | joint | Fc identified (plant Fc / static) | RMS err, levels' speeds | max err below the levels | "
       "off > 10 % of static below [rad/s] | unsteady levels |\n|---|---|---|---|---|---|---|---|\n";
  for (const FrictionFormSweepRow& r : rows) {
    s << "| " << r.parameter << " | " << format_fixed(r.value, 3) << " | " << r.joint << " | ";
    if (!r.valid) {
      s << "INVALID: " << r.invalid_reason << " |||||\n";
      continue;
    }
    s << format_fixed(r.coulomb_identified_Nm, 3) << " (" << format_fixed(r.coulomb_plant_Nm, 3) << " / "
      << format_fixed(r.static_plant_Nm, 3) << ") | " << format_fixed(r.error.rms_levels_Nm, 3) << " ("
      << pct_of(r.error.rms_levels_Nm, r.static_plant_Nm) << ") | " << format_fixed(r.error.max_low_Nm, 3) << " | "
      << format_fixed(r.error.ten_percent_below_rad_s, 4) << " | " << r.error.unsteady_levels << "/" << r.levels_total << " |\n";
  }
  s << "\n";
  // Per parameter and joint: how the numbers move over the range (computed, not asserted).
  std::vector<std::pair<std::string, int>> groups;
  for (const FrictionFormSweepRow& r : rows) {
    if (std::find(groups.begin(), groups.end(), std::make_pair(r.parameter, r.joint)) == groups.end()) groups.push_back({r.parameter, r.joint});
  }
  for (const auto& [parameter, joint] : groups) {
    std::vector<const FrictionFormSweepRow*> valid;
    int invalid = 0;
    for (const FrictionFormSweepRow& r : rows) {
      if (r.parameter != parameter || r.joint != joint) continue;
      if (r.valid) valid.push_back(&r); else ++invalid;
    }
    s << "- " << parameter << ", joint " << joint << ": ";
    if (valid.size() < 2) {
      s << valid.size() << " valid run(s), " << invalid << " invalid: no trend to state.\n";
      continue;
    }
    bool rising = true;
    for (std::size_t k = 1; k < valid.size(); ++k) rising = rising && valid[k]->error.rms_levels_Nm >= valid[k - 1]->error.rms_levels_Nm;
    const FrictionFormSweepRow& a = *valid.front();
    const FrictionFormSweepRow& b = *valid.back();
    s << "from " << format_fixed(a.value, 3) << " to " << format_fixed(b.value, 3) << " the RMS fit error over the levels' speeds goes from "
      << format_fixed(a.error.rms_levels_Nm, 3) << " to " << format_fixed(b.error.rms_levels_Nm, 3) << " N.m ("
      << pct_of(a.error.rms_levels_Nm, a.static_plant_Nm) << " to " << pct_of(b.error.rms_levels_Nm, b.static_plant_Nm) << " of static)"
      << (rising ? ", rising at every step" : ", not monotonically") << "; the speed below which the model is off by more than 10 % of "
      << "static goes from " << format_fixed(a.error.ten_percent_below_rad_s, 4) << " to " << format_fixed(b.error.ten_percent_below_rad_s, 4)
      << " rad/s; unsteady levels from " << a.error.unsteady_levels << " to " << b.error.unsteady_levels << " of " << b.levels_total
      << "; " << invalid << " invalid run(s).\n";
  }
  return s.str();
}

}  // namespace phri
