#pragma once
// Friction identification as a test of its model's form (issue 39). The identified model is
//
//   e = c0 + tau_c sign(qd) + tau_v qd                 (friction_identification.hpp)
//
// and the default plant's friction has exactly that form (sim/stick_slip_friction.hpp), so a good fit
// there proves little. Here the plant is given another form, a Stribeck curve and a position-dependent
// ripple (StickSlipFriction's sliding form):
//
//   tau_f(q, v) = (tau_c + (tau_s - tau_c) exp(-(|v| / v_s)^delta) + a_r tau_c sin(n_r q + phi)) sign(v) + tau_v v
//
// and the identified model is compared with the plant's true steady sliding friction, averaged over
// position (the ripple's mean is 0): RMS and maximum error over the speeds the levels covered and
// over the low speeds they did not (breakaway speed to the slowest level), the error at the breakaway
// speed (the model's sign step against the curve's tau_s), and how far the measured levels scatter
// about the true mean curve (the ripple, which the model has no term for).
//
// Values (no published number for the Gen3's drives; kinova_gen3_dynamics.md: the reducer type is
// NOT FOUND, the paper calls the friction "usually in the harmonic drive"):
// * v_s: unknown, and no source found for a harmonic drive's Stribeck velocity on the output side
//   (Armstrong-Helouvry, Dupont & Canudas de Wit 1994 survey the form, not a Gen3 value). Swept over
//   0.005-0.1 rad/s (the plausible range); the default 0.02 rad/s is the range's middle
//   (geometric), and the sweep shows the result over the range instead of trusting one value.
// * delta = 2 (the Gaussian Stribeck curve, the survey's common choice).
// * tau_s / tau_c = 1.2: the top of the range friction_perturbation.hpp already gives the plant (the
//   paper found static and Coulomb "small enough [a difference] to model them with the same value").
// * ripple: n_r = 200 per joint revolution, i.e. twice per wave-generator turn at gear ratio 100 (the
//   flexspline's two meshing zones; a harmonic drive is assumed, as the paper does; position-dependent
//   friction of harmonic drives: Taghirad & Belanger 1998); amplitude a_r unknown, 0-20 % of Coulomb
//   taken as plausible, default 10 %.
#include <phri/sim/stick_slip_friction.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct FrictionLevel;
struct JointFrictionEstimate;
struct FrictionIdentificationResult;
struct FrictionIdentificationOptions;
struct SimRobotConfig;

/// The form of the plant's sliding friction during the identification.
enum class PlantFrictionForm {
  kModelForm,       ///< the identified model's form (stick-slip, Coulomb + viscous): the default
  kStribeckRipple,  ///< Stribeck curve + position-dependent ripple
};

struct StribeckRippleSettings {
  double stribeck_velocity_rad_s = 0.02;  ///< v_s (unknown: see the sweep)
  double stribeck_exponent = 2.0;         ///< delta
  double static_to_coulomb = 1.2;         ///< tau_s / tau_c of every plant joint
  double ripple_fraction = 0.1;           ///< a_r, of Coulomb
  double ripple_cycles_per_rev = 200.0;   ///< n_r
  /// The sweeps over the two unknowns, one at a time (the other at its default): each value a
  /// sliding-only identification (no static search) of sweep_joints.
  std::vector<double> stribeck_velocity_sweep = {0.005, 0.01, 0.02, 0.05, 0.1};
  std::vector<double> ripple_fraction_sweep = {0.0, 0.1, 0.2};
  std::vector<int> sweep_joints = {1, 5};  ///< 1-based
  int sweep_speed_levels = 12;             ///< per direction
};

/// The identified model against the plant's true friction (computed only on a plant of another form).
struct ModelFormError {
  bool computed = false;
  double stribeck_velocity_rad_s = 0.0;
  double stribeck_exponent = 0.0;
  double ripple_Nm = 0.0;          ///< a_r tau_c
  double breakaway_velocity_rad_s = 0.0;
  double slowest_level_rad_s = 0.0;  ///< over the steady levels
  double fastest_level_rad_s = 0.0;
  /// model - truth over [slowest, fastest] level speed (the range the fit saw)
  double rms_levels_Nm = 0.0, max_levels_Nm = 0.0, max_levels_at_rad_s = 0.0;
  /// model - truth over [breakaway speed, slowest level] (speeds the levels did not reach)
  double rms_low_Nm = 0.0, max_low_Nm = 0.0;
  double error_at_breakaway_Nm = 0.0;  ///< model - truth at the breakaway speed (sign step vs curve)
  /// The model is off by more than 10 % of tau_s below this speed (0: nowhere in the range).
  double ten_percent_below_rad_s = 0.0;
  /// Steady levels about the true mean curve (plus the sensor offset): RMS and max |deviation| (the ripple).
  double level_scatter_rms_Nm = 0.0, level_scatter_max_Nm = 0.0;
  /// The plant's breakaway level where each static search started (static + ripple there).
  double static_here_positive_Nm = 0.0, static_here_negative_Nm = 0.0;
  int unsteady_levels = 0;
  double fastest_unsteady_target_rad_s = 0.0;  ///< the fastest run-up speed among the unsteady levels (0: none)
  /// The plant's mean curve falls with speed below this (no constant current holds a speed there; 0: nowhere).
  double negative_slope_below_rad_s = 0.0;
};

/// Applies the Stribeck + ripple form to the plant: the sliding form and tau_s = ratio tau_c per joint.
void apply_stribeck_ripple(const StribeckRippleSettings& s, SimRobotConfig& plant);

/// The plant's true steady sliding friction at velocity v, averaged over position (ripple removed).
double mean_sliding_friction(const StickSlipFriction::Parameters& dry, double viscous_Nms_per_rad, double v);

/// The comparison of one joint's identified model with the plant's true friction; `levels` are the
/// joint's levels, q_static_positive/negative where its static searches started.
ModelFormError model_form_error(const JointFrictionEstimate& e, const std::vector<FrictionLevel>& levels,
                                const StickSlipFriction::Parameters& dry, double q_static_positive,
                                double q_static_negative);

/// One row of a sweep: `parameter` ("v_s" or "a_r") set to `value`.
struct FrictionFormSweepRow {
  std::string parameter;
  double value = 0.0;
  int joint = 0;
  bool valid = false;
  std::string invalid_reason;
  double coulomb_identified_Nm = 0.0, coulomb_plant_Nm = 0.0, static_plant_Nm = 0.0;
  double viscous_identified_Nms_per_rad = 0.0, viscous_plant_Nms_per_rad = 0.0;
  int levels_used = 0, levels_total = 0;
  ModelFormError error;
};

/// The sweeps over v_s and a_r (options.stribeck_ripple's lists), each value a sliding-only identification.
std::vector<FrictionFormSweepRow> friction_form_sweeps(const FrictionIdentificationOptions& options, std::ostream* progress);

/// Per-joint CSV and markdown of the form comparison, the sweep's CSV and markdown; sentences computed
/// from the numbers.
std::string model_form_csv(const FrictionIdentificationResult& r);
std::string model_form_markdown(const FrictionIdentificationResult& r);
std::string sweep_csv(const std::vector<FrictionFormSweepRow>& rows);
std::string sweep_markdown(const std::vector<FrictionFormSweepRow>& rows);

}  // namespace phri
