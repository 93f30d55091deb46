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
// factor (6 x 6). Near a singularity one direction is weak, cycle after cycle, and its direction
// moves little in a millisecond: W = I - (1 - f_w) u_w u_w^T is then updated from the last u_w by
// Rayleigh-quotient iteration (cubic convergence, two or three 6 x 6 solves) and accepted only when
// checked exact: the residual |A u - mu u| at rounding level, mu below sigma_0^2, and every other
// eigenvalue at or above it (A - sigma_0^2 I + c u u^T has a Cholesky factor). Otherwise (first
// cycle near the singularity, two weak directions, a check failing) the eigen-decomposition decides,
// as it always did.
//
// Far from a singularity most cycles need no test at all. Weyl's inequality for singular values,
// sigma_i(J) >= sigma_i(J_c) - ||J - J_c||_2 >= sigma_i(J_c) - ||J - J_c||_F, carries a certificate
// sigma_min(J_c) >= b (a Cholesky factor of J_c J_c^T - b^2 I, b = 4 or 2 sigma_0) to every later J
// with ||J - J_c||_F < b - sigma_0: the same answer as the test, for 42 multiply-adds. The arm moves
// J by ~1e-3 a millisecond; the certificate lasts tens of cycles. Fixed-size, no allocation.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace phri {

class SingularDirectionWeight {
public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  /// sigma_0 [m/rad and rad/rad, J's rows mix both]: 0 turns the weighting off.
  /// num_joints: the Jacobians' columns, for the certificate's workspace (another width is tested
  /// every cycle, as without a certificate).
  explicit SingularDirectionWeight(double sigma_threshold = 0.0, Eigen::Index num_joints = 0)
      : sigma0_(std::max(0.0, sigma_threshold)), certified_jacobian_(Eigen::MatrixXd::Zero(6, num_joints)) {}

  /// True when some singular value of J (6 x nv) is below sigma_0: weight() is then W.
  /// False: W is the identity (not formed).
  bool update(const Eigen::MatrixXd& jacobian) {
    active_ = false;
    if (sigma0_ <= 0.0) return false;
    const bool same_width = jacobian.cols() == certified_jacobian_.cols();
    if (certified_margin_ > 0.0 && same_width &&
        (jacobian - certified_jacobian_).squaredNorm() < certified_margin_ * certified_margin_) {
      ++certified_skips_;
      return false;
    }
    certified_margin_ = 0.0;
    jjt_.noalias() = jacobian * jacobian.transpose();
    const double threshold = sigma0_ * sigma0_;
    // Near a singularity last cycle: the tracked weak direction, checked exact, decides at once.
    if (has_weak_direction_ && track_weak_direction(threshold)) return active_ = true;
    // Every sigma_i >= sigma_0 exactly when J J^T - sigma_0^2 I is positive definite (Sylvester):
    // a 6 x 6 Cholesky decides it; the eigen-decomposition only runs when some sigma_i is below.
    // After a pass, 2 sigma_0 and then 4 sigma_0 are tried for the certificate above.
    if (positive_definite_above(sigma0_)) {
      has_weak_direction_ = false;
      if (same_width) {
        for (const double bound : {2.0 * sigma0_, 4.0 * sigma0_}) {
          if (!positive_definite_above(bound)) break;
          certified_margin_ = bound - sigma0_;
        }
        if (certified_margin_ > 0.0) certified_jacobian_ = jacobian;
      }
      return false;
    }
    active_ = decompose(threshold);
    return active_;
  }

  bool active() const { return active_; }
  const Matrix6d& weight() const { return weight_; }
  /// sigma_min of the last update() that returned true.
  double smallest_singular_value() const { return smallest_singular_value_; }
  double threshold() const { return sigma0_; }

  /// Updates since construction that the eigen-decomposition decided (the rest: tracked or skipped).
  long decompositions() const { return decompositions_; }
  /// Updates since construction that Weyl's certificate answered without a test.
  long certified_skips() const { return certified_skips_; }

private:
  // Whether J J^T - bound^2 I has a Cholesky factor: every singular value of J above bound.
  bool positive_definite_above(double bound) {
    shifted_ = jjt_;
    shifted_.diagonal().array() -= bound * bound;
    llt_.compute(shifted_);
    return llt_.info() == Eigen::Success;
  }

  // The eigen-decomposition of J J^T; remembers the weak direction when there is exactly one.
  bool decompose(double threshold) {
    ++decompositions_;
    eigen_.compute(jjt_);
    const Eigen::Matrix<double, 6, 1>& lambda = eigen_.eigenvalues();  // ascending
    has_weak_direction_ = lambda[0] < threshold && lambda[1] >= threshold;
    if (lambda[0] >= threshold) return false;
    if (has_weak_direction_) weak_ = eigen_.eigenvectors().col(0);
    for (int i = 0; i < 6; ++i) factor_[i] = std::clamp(lambda[i] / threshold, 0.0, 1.0);
    weight_.noalias() = eigen_.eigenvectors() * factor_.asDiagonal() * eigen_.eigenvectors().transpose();
    smallest_singular_value_ = std::sqrt(std::max(0.0, lambda[0]));
    return true;
  }

  // Rayleigh-quotient iteration from the last weak direction; true (W formed) only when the result
  // is checked to be the one eigenvalue below the threshold, to rounding.
  bool track_weak_direction(double threshold) {
    const double scale = jjt_.norm() + threshold;
    Eigen::Matrix<double, 6, 1> u = weak_;
    double mu = u.dot(jjt_ * u);
    bool converged = (jjt_ * u - mu * u).norm() <= 1e-14 * scale;
    for (int iteration = 0; iteration < 4 && !converged; ++iteration) {
      shifted_ = jjt_;
      shifted_.diagonal().array() -= mu;
      lu_.compute(shifted_);
      Eigen::Matrix<double, 6, 1> next = lu_.solve(u);
      const double norm = next.norm();
      if (!std::isfinite(norm) || norm == 0.0) return false;
      u = next / norm;
      mu = u.dot(jjt_ * u);
      converged = (jjt_ * u - mu * u).norm() <= 1e-14 * scale;
    }
    if (!converged || mu >= threshold) return false;
    // Every other eigenvalue >= the threshold: A - t I with u's eigenvalue lifted by c > t is PD.
    shifted_ = jjt_;
    shifted_.diagonal().array() -= threshold;
    shifted_.noalias() += (2.0 * scale) * u * u.transpose();
    llt_.compute(shifted_);
    if (llt_.info() != Eigen::Success) return false;
    weak_ = u;
    const double lambda = std::max(0.0, mu);
    weight_.setIdentity();
    weight_.noalias() -= (1.0 - std::min(1.0, lambda / threshold)) * u * u.transpose();
    smallest_singular_value_ = std::sqrt(lambda);
    return true;
  }

  double sigma0_;
  bool active_ = false;
  bool has_weak_direction_ = false;  // the last update had exactly one eigenvalue below the threshold
  long decompositions_ = 0;
  long certified_skips_ = 0;
  Eigen::MatrixXd certified_jacobian_;  // J_c: sigma_min(J_c) >= sigma_0 + certified_margin_
  double certified_margin_ = 0.0;       // 0: no certificate
  Eigen::Matrix<double, 6, 1> weak_ = Eigen::Matrix<double, 6, 1>::Zero();
  double smallest_singular_value_ = 0.0;
  Matrix6d jjt_ = Matrix6d::Zero();
  Matrix6d shifted_ = Matrix6d::Zero();
  Matrix6d weight_ = Matrix6d::Identity();
  Eigen::Matrix<double, 6, 1> factor_ = Eigen::Matrix<double, 6, 1>::Ones();
  Eigen::LLT<Matrix6d> llt_{6};
  Eigen::PartialPivLU<Matrix6d> lu_{6};
  Eigen::SelfAdjointEigenSolver<Matrix6d> eigen_{6};
};

}  // namespace phri
