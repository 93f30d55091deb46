#include <phri/model/data.hpp>

namespace phri {

Data::Data(const Model& model)
    : body_placements(static_cast<std::size_t>(model.nq()), Eigen::Isometry3d::Identity()),
      frame_placements(static_cast<std::size_t>(model.num_frames()), Eigen::Isometry3d::Identity()),
      motion_subspace(Matrix6Xd::Zero(6, model.nv())),
      body_velocities(Matrix6Xd::Zero(6, model.nv())),
      body_accelerations(Matrix6Xd::Zero(6, model.nv())),
      body_inertias(static_cast<std::size_t>(model.nq())),
      composite_inertias(static_cast<std::size_t>(model.nq())),
      body_forces(Matrix6Xd::Zero(6, model.nv())),
      mass_matrix(Eigen::MatrixXd::Zero(model.nv(), model.nv())),
      mass_matrix_llt(model.nv()),
      mass_matrix_with_rotors_llt(model.nv()),
      tau(Eigen::VectorXd::Zero(model.nv())),
      nonlinear_effects(Eigen::VectorXd::Zero(model.nv())),
      gravity_torque(Eigen::VectorXd::Zero(model.nv())),
      coriolis_transpose_qd(Eigen::VectorXd::Zero(model.nv())) {}

}  // namespace phri
