#pragma once
// phri::QpProblem: the data of one dense QP
//
//   minimize 1/2 x'Hx + g'x   s.t.   A_eq x = b_eq,   l <= A x <= u,   lb <= x <= ub
//
// with H symmetric positive definite (only its lower triangle is read). A side at or beyond
// +-QpSettings::infinity (1e20 by default), or an empty l, u, lb or ub, is absent.
#include <Eigen/Core>

namespace phri {

struct QpProblem {
  Eigen::MatrixXd H;     // n x n
  Eigen::VectorXd g;     // n
  Eigen::MatrixXd A_eq;  // m_eq x n
  Eigen::VectorXd b_eq;  // m_eq
  Eigen::MatrixXd A;     // m_in x n
  Eigen::VectorXd l;     // m_in, or empty
  Eigen::VectorXd u;     // m_in, or empty
  Eigen::VectorXd lb;    // n, or empty
  Eigen::VectorXd ub;    // n, or empty

  // Allocates every member: zeros, and every side of every row and bound absent (+-infinity).
  void resize(Eigen::Index n, Eigen::Index m_eq, Eigen::Index m_in);
};

}  // namespace phri
