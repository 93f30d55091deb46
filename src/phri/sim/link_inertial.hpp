#pragma once
// phri::LinkInertial: mass, centre of mass and principal moments of one rigid body, as MuJoCo
// stores them (body_mass, body_ipos, body_inertia; the principal axes body_iquat are not touched),
// and the seeded model-mismatch perturbation of the simulated plant: the plant's links differ from
// the URDF the controller uses by up to a given fraction.
#include <phri/core/random_generator.hpp>

#include <Eigen/Core>

namespace phri {

struct LinkInertial {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();            ///< in the body frame
  Eigen::Vector3d principal_kgm2 = Eigen::Vector3d::Zero();   ///< principal moments about the COM

  /// Physical: positive mass and moments, and the triangle inequality I_a + I_b >= I_c for every
  /// permutation (a rigid body's moments satisfy it; equality for a planar lamina).
  bool is_physical() const {
    const Eigen::Vector3d& I = principal_kgm2;
    return mass_kg > 0.0 && (I.array() > 0.0).all() && I[0] + I[1] >= I[2] && I[1] + I[2] >= I[0] &&
           I[0] + I[2] >= I[1];
  }

  /// A perturbed copy: mass x (1 + u_m), each principal moment x (1 + u_i), each COM coordinate
  /// + u_c * max(|com|, 0.01 m), with u_m, u_i, u_c uniform in [-fraction, fraction] (fractions in
  /// [0, 0.5]). The moments are then pulled back inside the triangle inequality if the draw left
  /// it (possible only for nearly planar bodies), so the result stays physical.
  LinkInertial perturbed(double mass_fraction, double com_fraction, double inertia_fraction,
                         RandomGenerator& rng) const {
    LinkInertial out = *this;
    out.mass_kg *= 1.0 + rng.uniform(-mass_fraction, mass_fraction);
    const double scale = std::max(com_m.norm(), 0.01);
    for (int k = 0; k < 3; ++k) out.com_m[k] += rng.uniform(-com_fraction, com_fraction) * scale;
    for (int k = 0; k < 3; ++k) out.principal_kgm2[k] *= 1.0 + rng.uniform(-inertia_fraction, inertia_fraction);
    Eigen::Vector3d& I = out.principal_kgm2;
    for (int k = 0; k < 3; ++k) {
      const double others = I[(k + 1) % 3] + I[(k + 2) % 3];
      if (I[k] > others) I[k] = others;
    }
    return out;
  }
};

}  // namespace phri
