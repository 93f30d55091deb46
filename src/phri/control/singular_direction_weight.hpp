#pragma once
// Weight of the end-effector task's directions near a kinematic singularity (not in the paper).
//
// The paper's end-effector term w_ee || J qdd + Jdot qd - xdd* ||^2 asks, along a direction u_i
// of task space whose singular value sigma_i is small, for a joint acceleration ~ (u_i . xdd*) /
// sigma_i: near an outstretched elbow (the Gen3's joints 3 and 5 aligned, q4 = 0) or along an
// arm's near self-motion, a millimetre of pose error or a push becomes tens of rad/s^2 on two
// joints in opposite directions, which the QP only bounds through the posture task's weight
// (w_0 / w_ee = 1e-4). Seen in the safety fuzz: joints 3 and 5 asked for +176 / -122 rad/s^2 while
// the Gen3 crossed q4 = 0 at speed (sigma_min 1e-4), joint 3 broke away from stiction at 150
// rad/s^2 and overshot its velocity limit; a 6-DoF arm pushed along its near self-motion stayed
// there, the end-effector task's millimetre pulling it further away against the posture spring.
//
// The remedy is the damped-least-squares idea with a variable damping (Nakamura & Hanafusa 1986;
// Chiaverini 1997: damping only where sigma is small), written as a task-space weight: with
// J J^T = U diag(sigma_i^2) U^T,
//
//   W = U diag(f_i) U^T,   f_i = min(1, (sigma_i / sigma_0)^2),
//
// and the task becomes w_ee || W^1/2 (J qdd + Jdot qd - xdd*) ||^2: directions with sigma_i >=
// sigma_0 keep their full weight, weaker ones fade out and the posture task governs the joint
// motion they would have asked for. W is a continuous function of J (f is continuous), so
// nothing steps when eigenvectors swap. When every sigma_i >= sigma_0 the weight is the identity
// and the task is exactly the paper's (W is then not even formed: update() says false).
//
// The test is cheap: every sigma_i >= sigma_0 exactly when J J^T - sigma_0^2 I has a Cholesky
// factor (6 x 6); only when it has none is the eigen-decomposition computed. Fixed-size, no
// allocation.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace phri {

class SingularDirectionWeight {
public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  /// sigma_0 [m/rad and rad/rad, J's rows mix both]: 0 turns the weighting off.
  explicit SingularDirectionWeight(double sigma_threshold = 0.0) : sigma0_(std::max(0.0, sigma_threshold)) {}

  /// True when some singular value of J (6 x nv) is below sigma_0: weight() is then W.
  /// False: W is the identity (not formed).
  bool update(const Eigen::MatrixXd& jacobian) {
    active_ = false;
    if (sigma0_ <= 0.0) return false;
    jjt_.noalias() = jacobian * jacobian.transpose();
    const double threshold = sigma0_ * sigma0_;
    // Every sigma_i >= sigma_0 exactly when J J^T - sigma_0^2 I is positive definite (Sylvester):
    // a 6 x 6 Cholesky decides it; the eigen-decomposition only runs when some sigma_i is below.
    shifted_ = jjt_;
    shifted_.diagonal().array() -= threshold;
    llt_.compute(shifted_);
    if (llt_.info() == Eigen::Success) return false;
    eigen_.compute(jjt_);
    const Eigen::Matrix<double, 6, 1>& lambda = eigen_.eigenvalues();
    if (lambda.minCoeff() >= threshold) return false;
    for (int i = 0; i < 6; ++i) factor_[i] = std::clamp(lambda[i] / threshold, 0.0, 1.0);
    weight_.noalias() = eigen_.eigenvectors() * factor_.asDiagonal() * eigen_.eigenvectors().transpose();
    smallest_singular_value_ = std::sqrt(std::max(0.0, lambda.minCoeff()));
    active_ = true;
    return true;
  }

  bool active() const { return active_; }
  const Matrix6d& weight() const { return weight_; }
  /// sigma_min of the last update() that returned true.
  double smallest_singular_value() const { return smallest_singular_value_; }
  double threshold() const { return sigma0_; }

private:
  double sigma0_;
  bool active_ = false;
  double smallest_singular_value_ = 0.0;
  Matrix6d jjt_ = Matrix6d::Zero();
  Matrix6d shifted_ = Matrix6d::Zero();
  Matrix6d weight_ = Matrix6d::Identity();
  Eigen::Matrix<double, 6, 1> factor_ = Eigen::Matrix<double, 6, 1>::Ones();
  Eigen::LLT<Matrix6d> llt_{6};
  Eigen::SelfAdjointEigenSolver<Matrix6d> eigen_{6};
};

}  // namespace phri
