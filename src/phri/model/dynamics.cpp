// CRBA, RNEA and the combined pass, in world coordinates (see spatial.hpp).
// For a chain, body i's parent is body i-1, so the backward sweeps are plain running sums.
#include <phri/model/algorithms.hpp>

#include <array>
#include <cmath>

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

// An inertia about the world origin as its ten parameters: mass, first moment h, upper triangle
// of the symmetric rotational inertia I. Plain scalars, so that the CRBA's running sum stays in
// registers: a WorldInertia went through the stack in pieces, and reading it back whole stalled on
// store forwarding, which was most of the CRBA's own time.
struct InertiaParameters {
  double mass = 0.0;
  double hx = 0.0, hy = 0.0, hz = 0.0;
  double ixx = 0.0, iyy = 0.0, izz = 0.0, ixy = 0.0, ixz = 0.0, iyz = 0.0;

  static InertiaParameters of(const WorldInertia& w) {
    const Eigen::Matrix3d& r = w.rotational;
    return {w.mass, w.first_moment.x(), w.first_moment.y(), w.first_moment.z(),
            r(0, 0), r(1, 1), r(2, 2), r(0, 1), r(0, 2), r(1, 2)};
  }
  void add(const InertiaParameters& o) {
    mass += o.mass;
    hx += o.hx;
    hy += o.hy;
    hz += o.hz;
    ixx += o.ixx;
    iyy += o.iyy;
    izz += o.izz;
    ixy += o.ixy;
    ixz += o.ixz;
    iyz += o.iyz;
  }
  void store(WorldInertia& out) const {
    out.mass = mass;
    out.first_moment << hx, hy, hz;
    out.rotational << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
  }
  /// The momentum for the unit motion s = (v; w): (m v - h x w; I w + h x v), as WorldInertia::apply.
  std::array<double, 6> apply(const double* s) const {
    const double vx = s[0], vy = s[1], vz = s[2], wx = s[3], wy = s[4], wz = s[5];
    return {mass * vx - (hy * wz - hz * wy), mass * vy - (hz * wx - hx * wz), mass * vz - (hx * wy - hy * wx),
            ixx * wx + ixy * wy + ixz * wz + (hy * vz - hz * vy), ixy * wx + iyy * wy + iyz * wz + (hz * vx - hx * vz),
            ixz * wx + iyz * wy + izz * wz + (hx * vy - hy * vx)};
  }
};

// A body's inertia about the world origin, as update_body_inertias computes it. The placement's
// 4 x 4 matrix holds R's columns as 4-vectors ending in 0, so c = R com + p and R Icom R^T are
// 4-wide multiply-adds, a third of the scalar ones. Forced inline: GCC keeps it out of the CRBA's
// loop otherwise, and the call spills the running sum (that part of a 30-DoF CRBA: ~10% slower).
[[gnu::always_inline]] inline InertiaParameters body_inertia_in_world(const Inertia& local,
                                                                   const Eigen::Isometry3d& placement) {
  const auto rotation = placement.matrix().leftCols<3>();  // (R; 0)
  const Eigen::Vector4d c = rotation * local.com + placement.matrix().col(3);
  const Eigen::Matrix<double, 4, 3> turned = rotation * local.inertia_com;
  const Eigen::Matrix<double, 4, 3> rotated = turned * rotation.topRows<3>().transpose();  // (R Icom R^T; 0)
  const double m = local.mass;
  // Parallel-axis theorem from the centre of mass to the world origin: + m (|c|^2 Id - c c^T).
  return {m, m * c.x(), m * c.y(), m * c.z(),
          rotated(0, 0) + m * (c.y() * c.y() + c.z() * c.z()), rotated(1, 1) + m * (c.x() * c.x() + c.z() * c.z()),
          rotated(2, 2) + m * (c.x() * c.x() + c.y() * c.y()), rotated(0, 1) - m * c.x() * c.y(),
          rotated(0, 2) - m * c.x() * c.z(), rotated(1, 2) - m * c.y() * c.z()};
}

// Composite inertias and M(q) = S^T Ic S from the last body down (entries (j, i), j <= i, use the
// composite of i), with F_i = Ic_i S_i in scalars too; body_inertia(i) is body i's inertia about
// the world origin.
template <class BodyInertia>
void composite_rigid_body(const Model& model, Data& data, const BodyInertia& body_inertia) {
  InertiaParameters composite;
  for (int i = model.nq() - 1; i >= 0; --i) {
    composite.add(body_inertia(i));
    composite.store(data.composite_inertias[static_cast<std::size_t>(i)]);
    const std::array<double, 6> f = composite.apply(&data.motion_subspace(0, i));
    for (int j = 0; j <= i; ++j) {
      const double* s = &data.motion_subspace(0, j);
      const double m = s[0] * f[0] + s[1] * f[1] + s[2] * f[2] + s[3] * f[3] + s[4] * f[4] + s[5] * f[5];
      data.mass_matrix(j, i) = m;
      data.mass_matrix(i, j) = m;
    }
    data.mass_matrix(i, i) += model.joint(i).armature;
  }
}

// The CRBA on the inertias update_body_inertias left in data (compute_all_terms).
void composite_rigid_body(const Model& model, Data& data) {
  composite_rigid_body(model, data, [&data](int i) {
    return InertiaParameters::of(data.body_inertias[static_cast<std::size_t>(i)]);
  });
}

// The CRBA straight from the body placements: each body's inertia is computed where it is added,
// and data.body_inertias (the Newton-Euler passes' input, which they compute themselves) is left alone.
void composite_rigid_body_from_placements(const Model& model, Data& data) {
  composite_rigid_body(model, data, [&model, &data](int i) {
    return body_inertia_in_world(model.body_inertia(i), data.body_placements[static_cast<std::size_t>(i)]);
  });
}

// I_i v_i, the body's momentum (WorldInertia::apply), for every backward sweep (Newton-Euler and
// C^T qd), with each multiply-add an explicit fma: left to itself GCC contracts them into FMAs
// differently where the result has one use and where it has two, and the sweeps that share this
// momentum must round it alike (nonlinear_effects, C^T qd and compute_all_terms agree to the bit).
[[gnu::always_inline]] inline Vector6d body_momentum(const Data& data, int i) {
  const WorldInertia& inertia = data.body_inertias[static_cast<std::size_t>(i)];
  const auto motion = data.body_velocities.col(i);
  const double vx = motion[0], vy = motion[1], vz = motion[2], wx = motion[3], wy = motion[4], wz = motion[5];
  const double hx = inertia.first_moment.x(), hy = inertia.first_moment.y(), hz = inertia.first_moment.z();
  const Eigen::Matrix3d& r = inertia.rotational;
  const double m = inertia.mass;
  Vector6d f;
  f[0] = std::fma(m, vx, -std::fma(hy, wz, -(hz * wy)));  // m v - h x w
  f[1] = std::fma(m, vy, -std::fma(hz, wx, -(hx * wz)));
  f[2] = std::fma(m, vz, -std::fma(hx, wy, -(hy * wx)));
  f[3] = std::fma(r(0, 0), wx, std::fma(r(0, 1), wy, std::fma(r(0, 2), wz, std::fma(hy, vz, -(hz * vy)))));  // I w + h x v
  f[4] = std::fma(r(1, 0), wx, std::fma(r(1, 1), wy, std::fma(r(1, 2), wz, std::fma(hz, vx, -(hx * vz)))));
  f[5] = std::fma(r(2, 0), wx, std::fma(r(2, 1), wy, std::fma(r(2, 2), wz, std::fma(hx, vy, -(hy * vx)))));
  return f;
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
    Vector6d f = inertia.apply(a) + force_cross(v, body_momentum(data, i));
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

// Leaves data.body_inertias as it was: only the Newton-Euler passes read it, after computing it.
const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q) {
  forward_kinematics(model, data, q);
  composite_rigid_body_from_placements(model, data);
  return data.mass_matrix;
}

bool compute_mass_matrix_cholesky(Data& data) {
  if (data.rotor_inertia.size() == 0) return data.mass_matrix_llt.compute(data.mass_matrix);
  SmallCholesky::compute_with_shifted(data.mass_matrix, data.rotor_inertia, data.mass_matrix_llt,
                                      data.mass_matrix_with_rotors_llt);
  return data.mass_matrix_llt.ok();
}

void mass_matrix_solve_in_place(const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  data.mass_matrix_llt.solve_in_place(x);
}

const Eigen::VectorXd& rnea(const Model& model, Data& data, const Eigen::VectorXd& q,
                            const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  forward_kinematics(model, data, q, qd, qdd);
  update_body_inertias(model, data);
  newton_euler_backward(model, data, &qdd, data.tau);
  return data.tau;
}

namespace {

// Placements, velocities, the drift accelerations (qdd = 0) and the bodies' world inertias.
void kinematics_with_drift(const Model& model, Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  forward_kinematics(model, data, q, qd);
  for (int i = 0; i < model.nq(); ++i) {
    const Vector6d s = data.motion_subspace.col(i);
    Vector6d a = motion_cross(data.body_velocities.col(i), s) * qd[i];
    if (i > 0) a += data.body_accelerations.col(i - 1);
    data.body_accelerations.col(i) = a;
  }
  update_body_inertias(model, data);
}

// h(q, qd) (the Newton-Euler sweep with qdd = 0), g(q) and C^T qd in one backward pass, each
// body's inertia and momentum I_i v_i formed once for the three.
void nonlinear_gravity_and_coriolis_transpose_backward(const Model& model, Data& data) {
  Vector6d base_acceleration;
  base_acceleration << -model.gravity(), Eigen::Vector3d::Zero();
  Vector6d gravity_force = Vector6d::Zero(), momentum = Vector6d::Zero();
  for (int i = model.nq() - 1; i >= 0; --i) {
    const WorldInertia& inertia = data.body_inertias[static_cast<std::size_t>(i)];
    const Vector6d v = data.body_velocities.col(i);
    const Vector6d momentum_i = body_momentum(data, i);
    const Vector6d a = data.body_accelerations.col(i) + base_acceleration;
    Vector6d f = inertia.apply(a) + force_cross(v, momentum_i);
    if (i + 1 < model.nq()) f += data.body_forces.col(i + 1);
    data.body_forces.col(i) = f;
    const auto s = data.motion_subspace.col(i);
    data.nonlinear_effects[i] = s.dot(f);
    gravity_force += inertia.apply(base_acceleration);
    data.gravity_torque[i] = s.dot(gravity_force);
    momentum += momentum_i;
    data.coriolis_transpose_qd[i] =
        i == 0 ? 0.0  // the base does not move
               : motion_cross(data.body_velocities.col(i - 1), data.motion_subspace.col(i)).dot(momentum);
  }
}

}  // namespace

// Through compute_all_terms' own passes, so that both give h to the bit (g and C^T qd come along).
const Eigen::VectorXd& nonlinear_effects(const Model& model, Data& data, const Eigen::VectorXd& q,
                                         const Eigen::VectorXd& qd) {
  kinematics_with_drift(model, data, q, qd);
  nonlinear_gravity_and_coriolis_transpose_backward(model, data);
  return data.nonlinear_effects;
}

const Eigen::VectorXd& compute_gravity(const Model& model, Data& data, const Eigen::VectorXd& q) {
  forward_kinematics(model, data, q);
  update_body_inertias(model, data);
  gravity_backward(model, data);
  return data.gravity_torque;
}

namespace {

// Body i's step of the backward pass of C^T qd: the subtree's momentum gains I_i v_i, and
// dT/dq_i = (v_{i-1} x S_i) . H_i.
void coriolis_transpose_step(const Data& data, int i, Vector6d& momentum, Eigen::VectorXd& out) {
  momentum += body_momentum(data, i);
  out[i] = i == 0 ? 0.0  // the base does not move
                  : motion_cross(data.body_velocities.col(i - 1), data.motion_subspace.col(i)).dot(momentum);
}

}  // namespace

const Eigen::VectorXd& coriolis_transpose_times_velocity(const Model& model, Data& data) {
  // T = sum_j 1/2 v_j' I_j v_j. Joint i turns every body j >= i; in body coordinates the inertia is
  // constant and the body velocity changes by -(S_i x v_{i-1}), so dT/dq_i = (v_{i-1} x S_i) . H_i
  // with H_i = sum_{j >= i} I_j v_j the momentum of the subtree (a running sum on a chain).
  Vector6d momentum = Vector6d::Zero();
  for (int i = model.nq() - 1; i >= 0; --i) coriolis_transpose_step(data, i, momentum, data.coriolis_transpose_qd);
  return data.coriolis_transpose_qd;
}

bool compute_all_terms(const Model& model, Data& data, const Eigen::VectorXd& q,
                       const Eigen::VectorXd& qd) {
  kinematics_with_drift(model, data, q, qd);
  nonlinear_gravity_and_coriolis_transpose_backward(model, data);
  update_frame_placements(model, data);
  composite_rigid_body(model, data);
  return compute_mass_matrix_cholesky(data);
}

}  // namespace phri
