#pragma once
// Rigid-body algorithms over (const Model&, Data&). None allocates: every buffer is in Data.
// Vectors q, qd, qdd have model.nq() entries; results go to Data (see data.hpp).
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>
#include <phri/model/spatial.hpp>

namespace phri {

/// Frame of expression of a frame's velocity, acceleration or Jacobian.
enum class ReferenceFrame {
  kWorld,              ///< spatial: velocity of the point at the world origin, world axes
  kLocalWorldAligned,  ///< velocity of the frame origin, world axes (the controller's choice)
  kLocal,              ///< velocity of the frame origin, frame axes
};

// ---- kinematics ------------------------------------------------------------------------
/// Body placements and joint motion subspaces.
void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q);
/// ... and body velocities.
void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& qd);
/// ... and body accelerations (gravity not included).
void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);
/// Placements of every frame from the body placements (after forward_kinematics).
void update_frame_placements(const Model& model, Data& data);

/// Frame velocity (after forward_kinematics with qd).
Vector6d frame_velocity(const Model& model, const Data& data, int frame_id, ReferenceFrame rf);
/// Classical acceleration of the frame (after forward_kinematics with qd and qdd). With qdd = 0
/// (as compute_all_terms leaves it) this is the acceleration bias J̇ q̇ of frame_jacobian(rf).
Vector6d frame_acceleration(const Model& model, const Data& data, int frame_id, ReferenceFrame rf);
/// J̇ q̇ of the frame: valid after compute_all_terms or forward_kinematics(q, qd, 0).
inline Vector6d frame_jdot_qdot(const Model& model, const Data& data, int frame_id, ReferenceFrame rf) {
  return frame_acceleration(model, data, frame_id, rf);
}

/// 6 x nv frame Jacobian (after forward_kinematics): frame velocity = J qd in convention rf.
void frame_jacobian(const Model& model, const Data& data, int frame_id, ReferenceFrame rf,
                    Eigen::Ref<Eigen::MatrixXd> jacobian);

/// 3 x nv linear Jacobian of the point of `body` (-1: the base) now at world position `point`:
/// its velocity in world axes is jacobian * qd (after forward_kinematics).
void body_point_linear_jacobian(const Model& model, const Data& data, int body, const Eigen::Vector3d& point,
                                Eigen::Ref<Eigen::MatrixXd> jacobian);
/// Velocity of that body point (after forward_kinematics with qd).
Eigen::Vector3d body_point_velocity(const Model& model, const Data& data, int body, const Eigen::Vector3d& point);
/// Classical acceleration of that body point with the accelerations in data; with qdd = 0 (after
/// compute_all_terms) it is the point's J̇ q̇.
Eigen::Vector3d body_point_jdot_qdot(const Model& model, const Data& data, int body, const Eigen::Vector3d& point);

// ---- dynamics --------------------------------------------------------------------------
/// Joint-space inertia matrix M(q) (composite rigid-body algorithm), into data.mass_matrix.
const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q);
/// Cholesky factor of data.mass_matrix (after crba); false if M is not positive definite. With
/// data.rotor_inertia set, also the factor of M + diag(rotor_inertia) (its ok() says if it holds).
bool compute_mass_matrix_cholesky(Data& data);
/// x <- M^-1 x using the factor (after compute_mass_matrix_cholesky).
void mass_matrix_solve_in_place(const Data& data, Eigen::Ref<Eigen::VectorXd> x);

/// Inverse dynamics tau = M(q) qdd + h(q, qd) (recursive Newton-Euler), into data.tau.
const Eigen::VectorXd& rnea(const Model& model, Data& data, const Eigen::VectorXd& q,
                            const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);
/// h(q, qd) = C(q, qd) qd + g(q), into data.nonlinear_effects (the same pass leaves g(q) and C^T qd in
/// data.gravity_torque and data.coriolis_transpose_qd, as compute_all_terms does).
const Eigen::VectorXd& nonlinear_effects(const Model& model, Data& data, const Eigen::VectorXd& q,
                                         const Eigen::VectorXd& qd);
/// g(q), into data.gravity_torque (body velocities and accelerations in data are kept).
const Eigen::VectorXd& compute_gravity(const Model& model, Data& data, const Eigen::VectorXd& q);

/// C(q, qd)^T qd, which equals dT/dq (T the kinetic energy): the term the generalized-momentum
/// observer needs, since dp/dt = tau + C^T qd - g for p = M qd. Uses the velocities and body
/// inertias in data (after compute_all_terms or nonlinear_effects); writes data.coriolis_transpose_qd.
const Eigen::VectorXd& coriolis_transpose_times_velocity(const Model& model, Data& data);

/// One pass for the controller: placements of bodies and frames, velocities, drift accelerations
/// (so frame_jdot_qdot works), M(q) and its Cholesky factor, h(q, qd), g(q) and C(q, qd)^T qd (as
/// coriolis_transpose_times_velocity gives it). Returns false if M is not positive definite (which a
/// valid model never gives).
bool compute_all_terms(const Model& model, Data& data, const Eigen::VectorXd& q,
                       const Eigen::VectorXd& qd);

}  // namespace phri
