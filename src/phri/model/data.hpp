#pragma once
// phri::Data: every buffer the model algorithms write, sized once from a Model.
// Frame conventions: "world" axes and origin; spatial quantities as in spatial.hpp.
#include <phri/model/model.hpp>
#include <phri/model/spatial.hpp>

#include <phri/model/small_cholesky.hpp>

#include <vector>

namespace phri {

struct Data {
  explicit Data(const Model& model);

  // ---- kinematics (forward_kinematics)
  std::vector<Eigen::Isometry3d> body_placements;   ///< oMi: body i in the world
  std::vector<Eigen::Isometry3d> frame_placements;  ///< oMf (update_frame_placements)
  Matrix6Xd motion_subspace;      ///< S_i: joint i's unit motion, world spatial, column i
  Matrix6Xd body_velocities;      ///< v_i, world spatial
  Matrix6Xd body_accelerations;   ///< a_i, world spatial, without gravity (drift when qdd = 0)

  // ---- dynamics
  std::vector<WorldInertia> body_inertias;       ///< body i about the world origin
  std::vector<WorldInertia> composite_inertias;  ///< bodies i..n-1 together (CRBA)
  Matrix6Xd body_forces;      ///< RNEA: net spatial force transmitted through joint i
  Eigen::MatrixXd mass_matrix;                 ///< M(q), armature included (crba)
  SmallCholesky mass_matrix_llt;  ///< compute_mass_matrix_cholesky
  /// The drives' reflected rotor inertias B, where a user sets them (empty by default): then
  /// compute_mass_matrix_cholesky also factors M + diag(B), what a torque step accelerates through
  /// rigid gears, in the same pass as M (UncancelledPush reads it).
  Eigen::VectorXd rotor_inertia;
  SmallCholesky mass_matrix_with_rotors_llt;  ///< M + diag(rotor_inertia); meaningless while it is empty
  Eigen::VectorXd tau;                ///< rnea output
  Eigen::VectorXd nonlinear_effects;  ///< h(q, qd) = C(q, qd) qd + g(q)
  Eigen::VectorXd gravity_torque;     ///< g(q)
  Eigen::VectorXd coriolis_transpose_qd;  ///< C(q, qd)^T qd (coriolis_transpose_times_velocity)
};

}  // namespace phri
