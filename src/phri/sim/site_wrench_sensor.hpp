#pragma once
// phri::SiteWrenchSensor: the values of a MuJoCo force and torque sensor pair on one site (the
// wrench the site's body receives from its parent, site frame), computed bit for bit as MuJoCo
// 2.2.2's sensor stage computes them (mj_rnePostConstraint, then mj_sensorAcc), but for that body
// only: the accelerations of its ancestors and the forces of its own subtree, where MuJoCo's stage
// runs the recursion over every body of the model. SimRobot samples its F/T sensor with it once per
// control period; MuJoCo's own stage cost ~5 % of a period (issue 44).
//
//   SiteWrenchSensor ft(m, force_sensor, torque_sensor);   // when reproduces(m, ...) (allocates)
//   double v[6];
//   std::memcpy(v, d->qvel, ...);  mj_step2(m, d);  ft.evaluate(m, d, v, force, torque);
//
// evaluate() reads the state of the last forward pass (positions, velocities `qvel`, accelerations
// qacc, applied forces, contacts). mj_step2 advances d->qvel after that pass (d->qacc and the rest
// stay), so the caller passes the velocities it saved before the step (after mj_forward: d->qvel).
// No allocation and no MuJoCo call that writes in evaluate().
#include <vector>

struct mjModel_;
struct mjData_;

namespace phri {

class SiteWrenchSensor {
public:
  SiteWrenchSensor() = default;
  /// `force_sensor`, `torque_sensor`: ids of MuJoCo sensors of type force and torque on one site.
  SiteWrenchSensor(const mjModel_* m, int force_sensor, int torque_sensor);

  /// Whether evaluate() gives exactly MuJoCo's readings of this pair: a force and a torque sensor on
  /// the same site, neither with a cutoff nor noise, and a model without equality constraints
  /// (their forces enter MuJoCo's external body forces, which are not reproduced here).
  static bool reproduces(const mjModel_* m, int force_sensor, int torque_sensor);

  bool bound() const { return site_ >= 0; }

  /// MuJoCo's readings of the force sensor (3) and of the torque sensor (3) for the state of d's last
  /// forward pass, whose velocities are `qvel` (nv).
  void evaluate(const mjModel_* m, const mjData_* d, const double* qvel, double force[3], double torque[3]);

private:
  void accelerate(const mjModel_* m, const mjData_* d, const double* qvel, int body);
  void add_external_forces(const mjModel_* m, const mjData_* d);
  void add_contact_forces(const mjModel_* m, const mjData_* d);
  void internal_forces(const mjModel_* m, const mjData_* d);

  int site_ = -1;
  int body_ = -1;                   // the site's body
  std::vector<int> accelerated_;    // its ancestors (world excluded) and its subtree, in id order
  std::vector<int> subtree_;        // the body and its descendants, in id order
  std::vector<unsigned char> in_subtree_;  // per body of the model
  // MuJoCo's cacc, cfrc_ext and cfrc_int (6 per body of the model; only the bodies above are written)
  std::vector<double> cacc_, cfrc_ext_, cfrc_int_;
};

}  // namespace phri
