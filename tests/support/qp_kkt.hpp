#pragma once
// The KKT conditions of a QpSolver result, as residuals each relative to the magnitudes of the
// terms it is made of (test_qp.cpp, test_logged_qps.cpp):
//   stationarity     H x + g + A_eq' y_eq + A' y_row + y_bound = 0
//   primal           A_eq x = b_eq, l <= A x <= u, lb <= x <= ub
//   dual             y <= 0 at a lower side, >= 0 at an upper side, 0 when inactive (per QpSolver's sides)
//   complementarity  y times the violation of its side
#include <phri/qp/qp_solver.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri::test {

struct Kkt {
  double stationarity = 0.0;
  double primal = 0.0;
  double dual = 0.0;
  double complementarity = 0.0;
  double worst() const { return std::max({stationarity, primal, dual, complementarity}); }
};

// A side at or beyond QpSettings' default infinity (1e20), or an empty vector, is absent.
inline double lower_of(const Eigen::VectorXd& v, Eigen::Index i) {
  return v.size() == 0 || v(i) <= -1e20 ? -std::numeric_limits<double>::infinity() : v(i);
}
inline double upper_of(const Eigen::VectorXd& v, Eigen::Index i) {
  return v.size() == 0 || v(i) >= 1e20 ? std::numeric_limits<double>::infinity() : v(i);
}

inline Kkt kkt_residuals(const QpProblem& p, const QpSolver& s) {
  using Eigen::Index;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Kkt r;
  const Eigen::VectorXd& x = s.x();
  const Eigen::VectorXd& y_eq = s.equality_multipliers();
  const Eigen::VectorXd& y_row = s.row_multipliers();
  const Eigen::VectorXd& y_b = s.bound_multipliers();
  const Eigen::MatrixXd h = p.H.selfadjointView<Eigen::Lower>();
  const Eigen::VectorXd hx = h * x;
  const Eigen::VectorXd eq_term = p.A_eq.transpose() * y_eq;
  const Eigen::VectorXd row_term = p.A.transpose() * y_row;
  const Eigen::VectorXd residual = hx + p.g + eq_term + row_term + y_b;
  const double grad_scale = std::max({1.0, hx.cwiseAbs().maxCoeff(), p.g.cwiseAbs().maxCoeff(),
                                      eq_term.size() ? eq_term.cwiseAbs().maxCoeff() : 0.0,
                                      row_term.cwiseAbs().maxCoeff(), y_b.cwiseAbs().maxCoeff()});
  r.stationarity = residual.cwiseAbs().maxCoeff() / grad_scale;

  double y_scale = 1.0;
  if (y_row.size()) y_scale = std::max(y_scale, y_row.cwiseAbs().maxCoeff());
  y_scale = std::max(y_scale, y_b.cwiseAbs().maxCoeff());

  const auto check = [&](double value, double lo, double hi, double magnitude, double y, QpActiveSide side) {
    const double below = std::isfinite(lo) ? (lo - value) / (1.0 + std::abs(lo) + magnitude) : -kInf;
    const double above = std::isfinite(hi) ? (value - hi) / (1.0 + std::abs(hi) + magnitude) : -kInf;
    r.primal = std::max({r.primal, below, above});
    // Sign of the multiplier against the reported side; inactive ones are exactly zero.
    double wrong = 0.0;
    if (side == QpActiveSide::kInactive) wrong = std::abs(y);
    if (side == QpActiveSide::kLower) wrong = std::max(y, 0.0);
    if (side == QpActiveSide::kUpper) wrong = std::max(-y, 0.0);
    if (side == QpActiveSide::kLower && !std::isfinite(lo)) wrong = kInf;
    if (side == QpActiveSide::kUpper && !std::isfinite(hi)) wrong = kInf;
    r.dual = std::max(r.dual, wrong / y_scale);
    if (y < 0.0) r.complementarity = std::max(r.complementarity, -y / y_scale * std::abs(below));
    if (y > 0.0) r.complementarity = std::max(r.complementarity, y / y_scale * std::abs(above));
  };
  for (Index i = 0; i < p.A_eq.rows(); ++i) {
    const double v = p.A_eq.row(i).dot(x);
    const double magnitude = p.A_eq.row(i).cwiseAbs().dot(x.cwiseAbs());
    r.primal = std::max(r.primal, std::abs(v - p.b_eq(i)) / (1.0 + std::abs(p.b_eq(i)) + magnitude));
  }
  for (Index i = 0; i < p.A.rows(); ++i) {
    check(p.A.row(i).dot(x), lower_of(p.l, i), upper_of(p.u, i), p.A.row(i).cwiseAbs().dot(x.cwiseAbs()), y_row(i),
          s.active_rows()[static_cast<std::size_t>(i)]);
  }
  for (Index j = 0; j < x.size(); ++j) {
    check(x(j), lower_of(p.lb, j), upper_of(p.ub, j), 0.0, y_b(j), s.active_bounds()[static_cast<std::size_t>(j)]);
  }
  return r;
}

}  // namespace phri::test
