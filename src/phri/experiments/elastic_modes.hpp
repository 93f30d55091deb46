#pragma once
// The elastic joint's own mode, the figure that explains a ringing seen on the elastic plant
// (issue 39). Per joint, the rotor (reflected inertia B) and the link side (the plant's M_ii at the
// posture, the other joints held) joined by the joint's torsional spring K form two masses on a
// spring; their one non-zero mode is
//     f = sqrt(K (1/M_ii + 1/B)) / (2 pi)
// (free-free two-mass oscillator, e.g. Spong 1987's flexible-joint model with the link decoupled),
// between the locked-link mode sqrt(K/B) / 2 pi (link held, the rotor rings) and the locked-rotor
// mode sqrt(K/M_ii) / 2 pi. The loops that close around the spring shift it; this is the open-loop
// plant's figure, computed from the plant's own parameters, not fitted to any run.
#include <string>
#include <vector>

namespace phri {

class SimRobot;

/// sqrt(K (1/J_link + 1/J_rotor)) / 2 pi [Hz]; 0 if an argument is not positive.
double two_mass_mode_hz(double stiffness_Nm_per_rad, double link_inertia_kgm2, double rotor_inertia_kgm2);

struct ElasticJointMode {
  int joint = 0;  ///< 1-based
  double stiffness_Nm_per_rad = 0.0, rotor_inertia_kgm2 = 0.0, link_inertia_kgm2 = 0.0;
  double locked_link_hz = 0.0;  ///< sqrt(K/B) / 2 pi
  double mode_hz = 0.0;         ///< two_mass_mode_hz
};

/// Every joint's figure from the plant as it stands (elastic joints; empty with a rigid plant):
/// K from its elasticity, B from its drives, M_ii from its joint-space inertia at the current posture.
std::vector<ElasticJointMode> elastic_joint_modes(const SimRobot& robot);

/// CSV, one row per joint: joint, stiffness, rotor and link inertia, locked-link and two-mass mode.
std::string elastic_modes_csv(const std::vector<ElasticJointMode>& modes);

}  // namespace phri
