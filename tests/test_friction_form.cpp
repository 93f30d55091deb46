// ctest-labels: unit physics
// A plant friction of another form than the identified model (issue 39): the Stribeck curve and the
// position-dependent ripple of StickSlipFriction against their closed form; with both off, the
// friction returns exactly what the elasto-plastic model returned before they existed (so the default
// plant is unchanged); and the identification on a Stribeck plant: the slowest levels cannot be held at
// constant current, the Coulomb estimate lands between the plant's Coulomb and static levels (at the
// bottom) and the fit error it reports is largest at the lowest speed.
#include <phri/config/sim_robot_config.hpp>
#include <phri/core/error.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/friction_model_form.hpp>
#include <phri/sim/stick_slip_friction.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

// The sliding level written out here, independently of StickSlipFriction (friction_model_form.hpp's formula).
double closed_form_level(double tau_c, double tau_s, double v_s, double delta, double ripple, double n_r, double phi, double q,
                         double speed) {
  return tau_c + (tau_s - tau_c) * std::exp(-std::pow(speed / v_s, delta)) + ripple * std::sin(n_r * q + phi);
}

phri::StickSlipFriction::Parameters stribeck_ripple_parameters() {
  phri::StickSlipFriction::Parameters p = phri::StickSlipFriction::presliding(2.0, 2.5, 0.03, 2.5e-4, 1e-3);
  p.stribeck_velocity_rad_s = 0.02;
  p.stribeck_exponent = 2.0;
  p.ripple_Nm = 0.2;
  p.ripple_cycles_per_rev = 200.0;
  p.ripple_phase_rad = 0.3;
  return p;
}

TEST(StribeckRippleFriction, SteadySlidingTorqueFollowsTheClosedForm) {
  const phri::StickSlipFriction::Parameters p = stribeck_ripple_parameters();
  for (int direction : {+1, -1}) {
    phri::StickSlipFriction f(p);
    f.reset(0.0);
    // Break away: a deflection beyond the largest breakaway level (static + ripple).
    const double q0 = direction * 1.5 * (p.static_Nm + p.ripple_Nm) / p.stiffness_Nm_per_rad;
    f.update(q0, direction * 0.5);
    ASSERT_TRUE(f.sliding());
    for (double speed : {0.005, 0.01, 0.02, 0.04, 0.1, 0.5}) {
      for (double q : {0.0, 0.004, 0.011, 0.5, -1.3}) {
        const double expected = closed_form_level(2.0, 2.5, 0.02, 2.0, 0.2, 200.0, 0.3, q, speed);
        EXPECT_NEAR(f.update(q, direction * speed), -direction * expected, 1e-12) << "speed " << speed << " q " << q;
        EXPECT_EQ(f.damping(), 0.0);  // sliding: no presliding damper
      }
    }
  }
  // Just past breakaway the curve starts at the static level (continuous), far beyond v_s it is Coulomb.
  EXPECT_NEAR(phri::StickSlipFriction::sliding_level(p, 0.0, 1e-6) - phri::StickSlipFriction::ripple(p, 0.0), 2.5, 1e-8);
  EXPECT_NEAR(phri::StickSlipFriction::sliding_level(p, 0.0, 0.5) - phri::StickSlipFriction::ripple(p, 0.0), 2.0, 1e-12);
}

TEST(StribeckRippleFriction, BreakawayLevelDependsOnPosition) {
  const phri::StickSlipFriction::Parameters p = stribeck_ripple_parameters();
  for (double anchor : {0.0, 0.004, 0.012}) {
    const double level = 2.5 + 0.2 * std::sin(200.0 * anchor + 0.3);
    EXPECT_NEAR(phri::StickSlipFriction::breakaway_level(p, anchor), level, 1e-12);
    phri::StickSlipFriction below(p), above(p);
    below.reset(anchor);
    above.reset(anchor);
    // The deflection is ~2e-5 rad: the level at the deflected position differs by ~1e-3 N.m at most.
    below.update(anchor + 0.99 * level / p.stiffness_Nm_per_rad, 0.0);
    EXPECT_FALSE(below.sliding());
    above.update(anchor + 1.01 * level / p.stiffness_Nm_per_rad, 0.0);
    EXPECT_TRUE(above.sliding());
  }
}

// StickSlipFriction::update as it was before the sliding form existed (commit ee7a8c7), kept here as
// the reference the default must reproduce bit for bit.
class OldStickSlip {
public:
  explicit OldStickSlip(const phri::StickSlipFriction::Parameters& p) : p_(p) {}
  double update(double q, double qd) {
    if (direction_ != 0) {
      const bool reversed = qd * direction_ < 0.0;
      const bool fast = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      reached_speed_ = reached_speed_ || fast;
      if (reversed || (reached_speed_ && !fast)) {
        direction_ = 0;
        reached_speed_ = false;
      } else {
        anchor_ = q - direction_ * p_.coulomb_Nm / p_.stiffness_Nm_per_rad;
        return -direction_ * p_.coulomb_Nm;
      }
    }
    const double spring = p_.stiffness_Nm_per_rad * (q - anchor_);
    if (std::abs(spring) > p_.static_Nm) {
      direction_ = spring > 0.0 ? 1 : -1;
      reached_speed_ = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      anchor_ = q - direction_ * p_.coulomb_Nm / p_.stiffness_Nm_per_rad;
      return -direction_ * p_.coulomb_Nm;
    }
    return -spring;
  }
  double damping() const { return direction_ == 0 ? p_.damping_Nms_per_rad : 0.0; }

private:
  phri::StickSlipFriction::Parameters p_;
  double anchor_ = 0.0;
  int direction_ = 0;
  bool reached_speed_ = false;
};

TEST(StribeckRippleFriction, OffByDefaultAndBitIdenticalToTheOldModel) {
  // The plant file's defaults leave the sliding form off.
  const phri::SimRobotConfig config = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  EXPECT_EQ(config.friction.stribeck_velocity_rad_s, 0.0);
  EXPECT_EQ(config.friction.ripple_fraction, 0.0);
  // A random walk through sticking, breakaway, sliding, reversal and re-sticking: the same doubles.
  const phri::StickSlipFriction::Parameters p = phri::StickSlipFriction::presliding(2.15, 2.4, 0.03, 2.5e-4, 1e-3);
  phri::StickSlipFriction now(p);
  now.reset(0.0);
  OldStickSlip old(p);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> jolt(0.0, 0.02);
  double q = 0.0, qd = 0.0;
  int slid = 0;
  for (int k = 0; k < 20000; ++k) {
    qd = 0.995 * qd + jolt(rng);
    if (k % 500 < 100) qd = 0.0;  // rests: it sticks again
    q += 2.5e-4 * qd + (k % 500 < 100 ? 1e-6 * (k % 7 - 3) : 0.0);
    const double a = now.update(q, qd);
    const double b = old.update(q, qd);
    ASSERT_EQ(a, b) << "step " << k;
    ASSERT_EQ(now.damping(), old.damping()) << "step " << k;
    slid += now.sliding() ? 1 : 0;
  }
  EXPECT_GT(slid, 1000);     // the walk did slide
  EXPECT_LT(slid, 19000);    // and did stick
}

TEST(StribeckRippleFriction, PlantKeysLoadAndAreRangeChecked) {
  std::ifstream file(kRoot + "/configs/plant_gen3.yaml");
  std::stringstream text;
  text << file.rdbuf();
  const std::string yaml = text.str();
  const std::string key = "    breakaway_velocity_rad_s: 0.001";
  const std::size_t at = yaml.find(key);
  ASSERT_NE(at, std::string::npos);
  auto with = [&](const std::string& extra) {
    std::string y = yaml;
    y.insert(at + key.size(), extra);
    return y;
  };
  const phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_string(
      with("\n    stribeck_velocity_rad_s: 0.03\n    stribeck_exponent: 1.5\n    ripple_fraction: 0.1\n"
           "    ripple_cycles_per_rev: 100\n    ripple_phase_rad: 0.5"),
      "plant_gen3.yaml", kRoot + "/configs");
  EXPECT_EQ(c.friction.stribeck_velocity_rad_s, 0.03);
  EXPECT_EQ(c.friction.stribeck_exponent, 1.5);
  EXPECT_EQ(c.friction.ripple_fraction, 0.1);
  EXPECT_EQ(c.friction.ripple_cycles_per_rev, 100.0);
  EXPECT_EQ(c.friction.ripple_phase_rad, 0.5);
  EXPECT_THROW(phri::SimRobotConfig::from_yaml_string(with("\n    ripple_fraction: 0.9"), "plant_gen3.yaml", kRoot + "/configs"),
               phri::ConfigError);
}

TEST(StribeckRippleFriction, IdentificationReportsTheModelsFormError) {
  phri::FrictionIdentificationOptions o;
  o.plant_config_path = kRoot + "/configs/plant_gen3.yaml";
  o.urdf_path = kRoot + "/robots/kinova_gen3/gen3.urdf";
  o.output_dir.clear();
  o.figure_script.clear();
  o.joints = {5};
  o.speed_levels = 5;
  o.static_bisection_steps = 7;
  o.friction_perturbation = 0.0;
  o.plant_friction = phri::PlantFrictionForm::kStribeckRipple;
  o.stribeck_ripple.stribeck_velocity_rad_s = 0.05;  // the curve reaches into the levels' speeds
  o.stribeck_ripple.ripple_fraction = 0.0;
  o.stribeck_ripple.stribeck_velocity_sweep.clear();
  o.stribeck_ripple.ripple_fraction_sweep.clear();
  std::ostringstream progress;
  const phri::FrictionIdentificationResult r = phri::identify_friction(o, &progress);
  std::printf("%s\n%s", progress.str().c_str(), phri::model_form_markdown(r).c_str());
  ASSERT_EQ(r.joints.size(), 1u);
  const phri::JointFrictionEstimate& e = r.joints[0];
  ASSERT_TRUE(e.valid) << e.invalid_reason;
  ASSERT_TRUE(e.form.computed);
  EXPECT_NEAR(e.plant.static_Nm, 1.2 * e.plant.coulomb_Nm, 1e-12);
  // Constant current cannot hold a speed where the curve falls faster than viscous friction rises:
  // the slowest levels are not steady, so the fit sees the curve's stable branch only and its Coulomb
  // level lands at or just above the plant's Coulomb level, below the static one.
  EXPECT_GE(e.form.unsteady_levels, 1);
  EXPECT_GT(e.form.negative_slope_below_rad_s, 0.0);
  EXPECT_LE(e.form.fastest_unsteady_target_rad_s, 0.2);
  EXPECT_GT(e.identified.coulomb_Nm, e.plant.coulomb_Nm - 0.01);
  EXPECT_LT(e.identified.coulomb_Nm, e.plant.static_Nm);
  // A nonzero fit error, largest at the lowest speed: at the breakaway speed the sign step sits under
  // the curve by about static - identified Coulomb, far more than anywhere in the levels' range.
  EXPECT_GT(e.form.max_low_Nm, 0.1 * e.plant.static_Nm);
  EXPECT_GT(e.form.max_low_Nm, 10.0 * e.form.max_levels_Nm);
  EXPECT_NEAR(e.form.error_at_breakaway_Nm, e.identified.coulomb_Nm - e.plant.static_Nm, 0.01);
  EXPECT_NEAR(e.form.max_low_Nm, std::abs(e.form.error_at_breakaway_Nm), 0.01);
  EXPECT_GT(e.form.ten_percent_below_rad_s, 0.0);
  EXPECT_LT(e.form.ten_percent_below_rad_s, e.form.slowest_level_rad_s);
  // The static search finds the plant's static level (no ripple here).
  EXPECT_NEAR(e.identified.static_Nm, e.plant.static_Nm, 0.05 * e.plant.static_Nm);
  std::printf("simulated %.1f s in %.2f s\n", r.simulated_s, r.wall_s);
}

TEST(StribeckRippleFriction, RejectsOutOfRangeSettings) {
  phri::FrictionIdentificationOptions o;
  o.plant_config_path = kRoot + "/configs/plant_gen3.yaml";
  o.urdf_path = kRoot + "/robots/kinova_gen3/gen3.urdf";
  o.output_dir.clear();
  o.plant_friction = phri::PlantFrictionForm::kStribeckRipple;
  o.stribeck_ripple.static_to_coulomb = 0.9;  // static below Coulomb
  EXPECT_THROW(phri::identify_friction(o, nullptr), phri::ConfigError);
  o.stribeck_ripple.static_to_coulomb = 1.2;
  o.stribeck_ripple.stribeck_velocity_sweep = {0.0};
  EXPECT_THROW(phri::identify_friction(o, nullptr), phri::ConfigError);
}

}  // namespace
