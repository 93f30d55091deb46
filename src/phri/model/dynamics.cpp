// CRBA, RNEA and the combined pass, in world coordinates (see spatial.hpp).
// For a chain, body i's parent is body i-1, so the backward sweeps are plain running sums.
#include <phri/model/algorithms.hpp>


namespace phri {
namespace {

void update_body_inertias(const Model& model, Data& data) {
  for (int i = 0; i < model.nq(); ++i) {
    const Inertia& local = model.body_inertia(i);
    const Eigen::Isometry3d& oMi = data.body_placements[static_cast<std::size_t>(i)];
    WorldInertia& w = data.body_inertias[static_cast<std::size_t>(i)];
    const Eigen::Vector3d c = oMi * local.com;
    w.mass = local.mass;
    w.first_moment = local.mass * c;
    // Parallel-axis theorem from the centre of mass to the world origin.
    w.rotational.noalias() = oMi.linear() * local.inertia_com * oMi.linear().transpose();
    w.rotational += local.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  }
}

// Composite inertias and M(q) = S^T Ic S (entries (j, i), j <= i, use the composite of i).
void composite_rigid_body(const Model& model, Data& data) {
  const int n = model.nq();
  for (int i = n - 1; i >= 0; --i) {
    WorldInertia& ic = data.composite_inertias[static_cast<std::size_t>(i)];
    ic = data.body_inertias[static_cast<std::size_t>(i)];
    if (i + 1 < n) ic += data.composite_inertias[static_cast<std::size_t>(i + 1)];
    const Vector6d force = ic.apply(data.motion_subspace.col(i));
    for (int j = 0; j <= i; ++j) {
      const double m = data.motion_subspace.col(j).dot(force);
      data.mass_matrix(j, i) = m;
      data.mass_matrix(i, j) = m;
    }
    data.mass_matrix(i, i) += model.joint(i).armature;
  }
}

// Backward Newton-Euler sweep with the body velocities and accelerations already in Data.
// Gravity enters as an upward acceleration of the base, (-g; 0).
void newton_euler_backward(const Model& model, Data& data, const Eigen::VectorXd* qdd,
                           Eigen::VectorXd& tau) {
  Vector6d base_acceleration;
  base_acceleration << -model.gravity(), Eigen::Vector3d::Zero();
  for (int i = model.nq() - 1; i >= 0; --i) {
    const WorldInertia& inertia = data.body_inertias[static_cast<std::size_t>(i)];
    const Vector6d v = data.body_velocities.col(i);
    const Vector6d a = data.body_accelerations.col(i) + base_acceleration;
    Vector6d f = inertia.apply(a) + force_cross(v, inertia.apply(v));
    if (i + 1 < model.nq()) f += data.body_forces.col(i + 1);
    data.body_forces.col(i) = f;
    tau[i] = data.motion_subspace.col(i).dot(f);
    if (qdd != nullptr) tau[i] += model.joint(i).armature * (*qdd)[i];
  }
}

// g(q) from the body inertias alone (velocities and accelerations in data are left untouched).
void gravity_backward(const Model& model, Data& data) {
  Vector6d base_acceleration;
  base_acceleration << -model.gravity(), Eigen::Vector3d::Zero();
  Vector6d force = Vector6d::Zero();
  for (int i = model.nq() - 1; i >= 0; --i) {
    force += data.body_inertias[static_cast<std::size_t>(i)].apply(base_acceleration);
    data.gravity_torque[i] = data.motion_subspace.col(i).dot(force);
  }
}

}  // namespace

const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q) {
  forward_kinematics(model, data, q);
  update_body_inertias(model, data);
  composite_rigid_body(model, data);
  return data.mass_matrix;
}

bool compute_mass_matrix_cholesky(Data& data) {
  data.mass_matrix_llt.compute(data.mass_matrix);
  return data.mass_matrix_llt.info() == Eigen::Success;
}

void mass_matrix_solve_in_place(const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  data.mass_matrix_llt.solveInPlace(x);
}

const Eigen::VectorXd& rnea(const Model& model, Data& data, const Eigen::VectorXd& q,
                            const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  forward_kinematics(model, data, q, qd, qdd);
  update_body_inertias(model, data);
  newton_euler_backward(model, data, &qdd, data.tau);
  return data.tau;
}

const Eigen::VectorXd& nonlinear_effects(const Model& model, Data& data, const Eigen::VectorXd& q,
                                         const Eigen::VectorXd& qd) {
  forward_kinematics(model, data, q, qd);
  for (int i = 0; i < model.nq(); ++i) {
    const Vector6d s = data.motion_subspace.col(i);
    Vector6d a = motion_cross(data.body_velocities.col(i), s) * qd[i];
    if (i > 0) a += data.body_accelerations.col(i - 1);
    data.body_accelerations.col(i) = a;
  }
  update_body_inertias(model, data);
  newton_euler_backward(model, data, nullptr, data.nonlinear_effects);
  return data.nonlinear_effects;
}

const Eigen::VectorXd& compute_gravity(const Model& model, Data& data, const Eigen::VectorXd& q) {
  forward_kinematics(model, data, q);
  update_body_inertias(model, data);
  gravity_backward(model, data);
  return data.gravity_torque;
}

const Eigen::VectorXd& coriolis_transpose_times_velocity(const Model& model, Data& data) {
  // T = sum_j 1/2 v_j' I_j v_j. Joint i turns every body j >= i; in body coordinates the inertia is
  // constant and the body velocity changes by -(S_i x v_{i-1}), so dT/dq_i = (v_{i-1} x S_i) . H_i
  // with H_i = sum_{j >= i} I_j v_j the momentum of the subtree (a running sum on a chain).
  Vector6d momentum = Vector6d::Zero();
  for (int i = model.nq() - 1; i >= 0; --i) {
    const WorldInertia& inertia = data.body_inertias[static_cast<std::size_t>(i)];
    momentum += inertia.apply(data.body_velocities.col(i));
    if (i == 0) {
      data.coriolis_transpose_qd[i] = 0.0;  // the base does not move
    } else {
      data.coriolis_transpose_qd[i] =
          motion_cross(data.body_velocities.col(i - 1), data.motion_subspace.col(i)).dot(momentum);
    }
  }
  return data.coriolis_transpose_qd;
}

bool compute_all_terms(const Model& model, Data& data, const Eigen::VectorXd& q,
                       const Eigen::VectorXd& qd) {
  nonlinear_effects(model, data, q, qd);  // placements, velocities, drift accelerations, inertias
  update_frame_placements(model, data);
  gravity_backward(model, data);
  composite_rigid_body(model, data);
  return compute_mass_matrix_cholesky(data);
}

}  // namespace phri
