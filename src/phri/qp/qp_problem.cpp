#include <phri/qp/qp_problem.hpp>

#include <limits>

namespace phri {

void QpProblem::resize(Eigen::Index n, Eigen::Index m_eq, Eigen::Index m_in) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  H.setZero(n, n);
  g.setZero(n);
  A_eq.setZero(m_eq, n);
  b_eq.setZero(m_eq);
  A.setZero(m_in, n);
  l.setConstant(m_in, -kInf);
  u.setConstant(m_in, kInf);
  lb.setConstant(n, -kInf);
  ub.setConstant(n, kInf);
}

}  // namespace phri
