#include <phri/experiments/friction_perturbation.hpp>

#include <phri/core/error.hpp>
#include <phri/core/random_generator.hpp>

namespace phri {
namespace {
constexpr std::uint64_t kFrictionStream = 11;  // separate from the plant's own noise streams
}

std::vector<SimRobotConfig::ActuatorOverride> perturbed_friction_overrides(const ActuatorTable& nominal,
                                                                           double fraction, std::uint64_t seed) {
  if (!(fraction >= 0.0 && fraction <= 0.9)) {
    throw ConfigError("<experiment options>", "friction_perturbation", "must be in [0, 0.9]");
  }
  RandomGenerator rng(seed, kFrictionStream);
  std::vector<SimRobotConfig::ActuatorOverride> out;
  for (int i = 0; i < nominal.size(); ++i) {
    const FrictionParameters& f = nominal[i].friction;
    // Always draw the three numbers, so joint i's plant does not depend on the fraction's sign
    // pattern of the joints before it.
    const double u1 = rng.uniform(-1.0, 1.0);
    const double u2 = rng.uniform(-1.0, 1.0);
    const double u3 = rng.uniform(0.0, 1.0);
    SimRobotConfig::ActuatorOverride o;
    o.joint = nominal[i].joint_name;
    const double coulomb = f.coulomb_Nm * (1.0 + fraction * u1);
    o.coulomb_Nm = coulomb;
    o.viscous_Nms_per_rad = f.viscous_Nms_per_rad * (1.0 + fraction * u2);
    const double ratio = f.coulomb_Nm > 0.0 ? f.static_Nm / f.coulomb_Nm : 1.0;  // nominal stiction ratio, >= 1
    o.static_Nm = coulomb * ratio * (1.0 + fraction * u3);
    out.push_back(o);
  }
  return out;
}

}  // namespace phri
