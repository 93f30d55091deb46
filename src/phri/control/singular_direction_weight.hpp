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
// The test is cheap: every sigma_i >= sigma_0 exactly when J J^T - sigma_0^2 I is positive
// definite, which a 6 x 6 root-free Cholesky (L D L^T, model/fixed_size_ldlt.hpp) decides.
// Near a singularity one direction is weak, cycle after cycle, and its direction
// moves little in a millisecond: W = I - (1 - f_w) u_w u_w^T is then updated from the last u_w by
// Rayleigh-quotient iteration (cubic convergence; one or two 6 x 6 factorisations in its
// Jacobi-Davidson form) and accepted only when checked exact: the residual |A u - mu u| at rounding
// level, mu below sigma_0^2, and every other eigenvalue at or above it (A - b I + c u u^T positive
// definite for b = sigma_0^2, or for b = 4 or 2 sigma_0^2 on an A within Weyl's distance).
// Otherwise (first cycle near the singularity, two weak directions, a check failing) the
// eigen-decomposition decides, as it always did.
//
// Far from a singularity most cycles need no test at all. Weyl's inequality for singular values,
// sigma_i(J) >= sigma_i(J_c) - ||J - J_c||_2 >= sigma_i(J_c) - ||J - J_c||_F, carries a certificate
// sigma_min(J_c) >= b (J_c J_c^T - b^2 I positive definite, b = 4 or 2 sigma_0) to every later J
// with ||J - J_c||_F < b - sigma_0: the same answer as the test, for 42 multiply-adds. The arm moves
// J by ~1e-3 a millisecond; the certificate lasts tens of cycles. Fixed-size, no allocation.
#include <phri/model/fixed_size_ldlt.hpp>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace phri {

class SingularDirectionWeight {
public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;

  /// sigma_0 [m/rad and rad/rad, J's rows mix both]: 0 turns the weighting off.
  /// num_joints: the Jacobians' columns, for the certificate's workspace (another width is tested
  /// every cycle, as without a certificate).
  explicit SingularDirectionWeight(double sigma_threshold = 0.0, Eigen::Index num_joints = 0)
      : sigma0_(std::max(0.0, sigma_threshold)), certified_jacobian_(Eigen::MatrixXd::Zero(6, num_joints)) {}

  /// True when some singular value of J (6 x nv) is below sigma_0: weight() is then W.
  /// False: W is the identity (not formed).
  bool update(const Eigen::MatrixXd& jacobian) {
    active_ = rank_one_ = false;
    if (sigma0_ <= 0.0) return false;
    const bool same_width = jacobian.cols() == certified_jacobian_.cols();
    if (certified_margin_ > 0.0 && same_width &&
        (jacobian - certified_jacobian_).squaredNorm() < certified_margin_ * certified_margin_) {
      ++certified_skips_;
      return false;
    }
    certified_margin_ = 0.0;
    // J J^T as a sum of the columns' fixed-size 6 x 6 outer products (the same sums in the same
    // order as the product, which for a dynamic J runs a coefficient-wise loop at run-time length).
    jjt_.setZero();
    for (Eigen::Index c = 0; c < jacobian.cols(); ++c) {
      const Vector6d column = jacobian.col(c);
      jjt_.noalias() += column * column.transpose();
    }
    const double threshold = sigma0_ * sigma0_;
    // Near a singularity last cycle: the tracked weak direction, checked exact, decides at once.
    if (has_weak_direction_ && track_weak_direction(threshold)) return active_ = rank_one_ = true;
    // Every sigma_i >= sigma_0 exactly when J J^T - sigma_0^2 I is positive definite (Sylvester):
    // a 6 x 6 L D L^T decides it; the eigen-decomposition only runs when some sigma_i is below.
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
  /// When active() and the weak direction was tracked: W = I - shrink u u^T with u = weak_direction()
  /// (W is formed too; W A is cheaper from this form). Otherwise false.
  bool rank_one() const { return rank_one_; }
  const Vector6d& weak_direction() const { return weak_; }
  double shrink() const { return shrink_; }
  const Matrix6d& weight() const { return weight_; }
  /// sigma_min of the last update() that returned true.
  double smallest_singular_value() const { return smallest_singular_value_; }
  double threshold() const { return sigma0_; }

  /// Updates since construction that the eigen-decomposition decided (the rest: tracked or skipped).
  long decompositions() const { return decompositions_; }
  /// Updates since construction that Weyl's certificate answered without a test.
  long certified_skips() const { return certified_skips_; }
  /// Tracked updates whose other eigenvalues Weyl's certificate answered without a factorisation.
  long second_certified() const { return second_certified_; }

private:
  // Whether J J^T - bound^2 I is positive definite: every singular value of J above bound.
  bool positive_definite_above(double bound) {
    shifted_ = jjt_;
    shifted_.diagonal().array() -= bound * bound;
    return ldlt_.compute(shifted_);
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

  // Rayleigh-quotient iteration from the last weak direction, in its Jacobi-Davidson form; true (W
  // formed) only when the result is checked to be the one eigenvalue below the threshold, to rounding.
  bool track_weak_direction(double threshold) {
    const double scale = jjt_.norm() + threshold;
    Vector6d u = weak_;
    Vector6d w = jjt_ * u;
    double mu = u.dot(w);
    Vector6d residual = w - mu * u;
    bool converged = residual.norm() <= 1e-14 * scale;
    for (int iteration = 0; iteration < 4 && !converged; ++iteration) {
      // The step d on u's complement: (P (A - mu I) P + c u u^T) d = -r, P = I - u u^T, r = A u - mu u
      // (u^T r = 0, so P (A - mu I) P = A - mu I - u r^T - r u^T). u + d is (A - mu I)^-1 u scaled,
      // the RQI step, but the matrix is positive definite while mu stays below A's second eigenvalue
      // (an L D L^T, no pivoting), and well conditioned where A - mu I is nearly singular.
      shifted_ = jjt_;
      shifted_.diagonal().array() -= mu;
      shifted_.noalias() -= u * residual.transpose();
      shifted_.noalias() -= residual * u.transpose();
      shifted_.noalias() += scale * u * u.transpose();
      if (!ldlt_.compute(shifted_)) return false;
      ldlt_.solve_in_place(residual);
      u -= residual;
      const double norm = u.norm();
      if (!std::isfinite(norm) || norm == 0.0) return false;
      u /= norm;
      w.noalias() = jjt_ * u;
      mu = u.dot(w);
      residual = w - mu * u;
      converged = residual.norm() <= 1e-14 * scale;
    }
    if (!converged || mu >= threshold || !others_at_or_above(threshold, u, scale)) return false;
    weak_ = u;
    const double lambda = std::max(0.0, mu);
    shrink_ = 1.0 - std::min(1.0, lambda / threshold);
    weight_.setIdentity();
    weight_.noalias() -= shrink_ * u * u.transpose();
    smallest_singular_value_ = std::sqrt(lambda);
    return true;
  }

  // Whether every eigenvalue of A = J J^T but the one along u is >= the threshold t. A + c u u^T - b I
  // positive definite gives lambda_1(A) >= b for any unit u (interlacing of a rank-one update), and by
  // Weyl lambda_1 moves by at most ||A - A_c||_F: a test at b = 4 t (or 2 t) carries to the next
  // cycles while A stays within 3 t (t) of the A_c it was made on. When both fail, lambda_1 < 2 t
  // (u being A's eigenvector to rounding) and a test at 4 t cannot pass before A has moved 2 t from
  // there: until then b = t is tested every cycle.
  bool others_at_or_above(double threshold, const Vector6d& u, double scale) {
    if (second_margin_ > 0.0 && (jjt_ - second_jjt_).squaredNorm() < second_margin_ * second_margin_) {
      ++second_certified_;
      return true;
    }
    second_margin_ = 0.0;
    const auto lifted_positive_definite = [&](double bound) {
      shifted_ = jjt_;
      shifted_.diagonal().array() -= bound;
      shifted_.noalias() += (2.0 * scale) * u * u.transpose();
      return ldlt_.compute(shifted_);
    };
    if (!second_ruled_out_ || (jjt_ - ruled_out_jjt_).squaredNorm() >= 4.0 * threshold * threshold) {
      second_ruled_out_ = false;
      for (const double factor : {4.0, 2.0}) {
        if (!lifted_positive_definite(factor * threshold)) continue;
        second_margin_ = (factor - 1.0) * threshold;
        second_jjt_ = jjt_;
        return true;
      }
      second_ruled_out_ = true;
      ruled_out_jjt_ = jjt_;
    }
    return lifted_positive_definite(threshold);
  }

  double sigma0_;
  bool active_ = false;
  bool rank_one_ = false;  // W = I - shrink_ weak_ weak_^T (the last update tracked the weak direction)
  double shrink_ = 0.0;
  bool has_weak_direction_ = false;  // the last update had exactly one eigenvalue below the threshold
  long decompositions_ = 0;
  long certified_skips_ = 0;
  Eigen::MatrixXd certified_jacobian_;  // J_c: sigma_min(J_c) >= sigma_0 + certified_margin_
  double certified_margin_ = 0.0;       // 0: no certificate
  Vector6d weak_ = Vector6d::Zero();
  Matrix6d second_jjt_ = Matrix6d::Zero();  // A_c: lambda_1(A_c) >= t + second_margin_
  double second_margin_ = 0.0;              // 0: no certificate
  bool second_ruled_out_ = false;            // lambda_1 < 2 t at ruled_out_jjt_
  Matrix6d ruled_out_jjt_ = Matrix6d::Zero();
  long second_certified_ = 0;
  double smallest_singular_value_ = 0.0;
  Matrix6d jjt_ = Matrix6d::Zero();
  Matrix6d shifted_ = Matrix6d::Zero();
  Matrix6d weight_ = Matrix6d::Identity();
  Eigen::Matrix<double, 6, 1> factor_ = Eigen::Matrix<double, 6, 1>::Ones();
  FixedSizeLdlt<6> ldlt_;
  Eigen::SelfAdjointEigenSolver<Matrix6d> eigen_{6};
};

}  // namespace phri
