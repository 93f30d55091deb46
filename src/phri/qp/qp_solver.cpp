// Goldfarb-Idnani dual active-set method. Notation of the paper: H = L L', the active normals N
// (q columns), J = L^-T Q and R upper triangular with Q' L^-1 N = [R; 0]; J1 = first q columns of
// J, J2 = the rest. For a constraint n'x >= b entering the active set, d = J'n, the primal step
// direction is z = J2 d2 and the dual one r = R^-1 d1 (Section 3 of the paper). Here L' is stored
// as the upper-triangular chol_, so the initial J is chol_^-1.
//
// Each row is scaled to unit length once per solve, which makes the violation test a distance and
// keeps R well balanced. A constraint k enters with sign +1 (normal a_k, active at its lower side)
// or -1 (normal -a_k, upper side); equalities use +1 and never leave.
#include <phri/qp/qp_solver.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// v.head(q) <- R^-1 v.head(q) for the leading q x q block of upper-triangular r.
void back_substitute(const Eigen::MatrixXd& r, Eigen::Index q, Eigen::VectorXd& v) {
  for (Eigen::Index i = q - 1; i >= 0; --i) {
    v(i) /= r(i, i);
    v.head(i) -= v(i) * r.col(i).head(i);
  }
}

// Columns a <- c a + s b and b <- -s a + c b.
void rotate_columns(Eigen::MatrixXd& m, Eigen::Index ia, Eigen::Index ib, double c, double s) {
  double* __restrict a = m.col(ia).data();
  double* __restrict b = m.col(ib).data();
  const Eigen::Index rows = m.rows();
  for (Eigen::Index t = 0; t < rows; ++t) {
    const double va = a[t];
    const double vb = b[t];
    a[t] = c * va + s * vb;
    b[t] = c * vb - s * va;
  }
}

template <typename Matrix>
Eigen::Index first_non_finite_row(const Matrix& m) {
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if (!m.row(i).allFinite()) return i;
  }
  return -1;
}

QpActiveSide side_of(std::int8_t sign) {
  return sign > 0 ? QpActiveSide::kLower : (sign < 0 ? QpActiveSide::kUpper : QpActiveSide::kInactive);
}

}  // namespace

void QpSolver::resize(Index n, Index m_eq, Index m_in) {
  n_ = std::max<Index>(n, 0);
  m_eq_ = std::max<Index>(m_eq, 0);
  m_in_ = std::max<Index>(m_in, 0);
  m_rows_ = m_eq_ + m_in_;
  const Index m_all = m_rows_ + n_;

  chol_.setZero(n_, n_);
  inv_chol_.setZero(n_, n_);
  has_factor_ = false;

  rows_.setZero(n_, m_rows_);
  row_scale_.setZero(m_rows_);
  lower_.setZero(m_all);
  upper_.setZero(m_all);
  g_.setZero(n_);
  null_row_infeasible_ = false;

  j_.setZero(n_, n_);
  r_.setZero(n_, n_);
  q_ = 0;
  active_.assign(static_cast<std::size_t>(n_), 0);
  sign_.assign(static_cast<std::size_t>(m_all), 0);
  u_.setZero(n_);
  d_.setZero(n_);
  dir_.setZero(n_);
  work_.setZero(n_);
  row_values_.setZero(m_in_);

  status_ = QpStatus::kInvalidInput;
  invalid_reason_ = QpInvalidReason::kNone;
  invalid_index_ = -1;
  iterations_ = 0;
  objective_ = 0.0;
  x_.setZero(n_);
  y_eq_.setZero(m_eq_);
  y_row_.setZero(m_in_);
  y_bound_.setZero(n_);
  row_sides_.assign(static_cast<std::size_t>(m_in_), QpActiveSide::kInactive);
  bound_sides_.assign(static_cast<std::size_t>(n_), QpActiveSide::kInactive);
}

// ------------------------------------------------------------------------------------ Hessian

QpInvalidReason QpSolver::set_hessian(const Eigen::Ref<const Eigen::MatrixXd>& hessian) {
  if (n_ == 0 || hessian.rows() != n_ || hessian.cols() != n_) return QpInvalidReason::kDimensionMismatch;
  Index pivot = -1;  // set_hessian reports no index: the last solve's results stay untouched
  return factorize(hessian, pivot);
}

QpInvalidReason QpSolver::set_hessian_factor(const Eigen::Ref<const Eigen::MatrixXd>& factor_l) {
  has_factor_ = false;
  if (n_ == 0 || factor_l.rows() != n_ || factor_l.cols() != n_) return QpInvalidReason::kDimensionMismatch;
  for (Index c = 0; c < n_; ++c) {
    if (!factor_l.col(c).tail(n_ - c).allFinite() || !(factor_l(c, c) > 0.0)) {
      return QpInvalidReason::kInvalidHessianFactor;
    }
  }
  chol_.triangularView<Eigen::Upper>() = factor_l.transpose();
  invert_factor();
  has_factor_ = true;
  return QpInvalidReason::kNone;
}

QpInvalidReason QpSolver::factorize(const Eigen::Ref<const Eigen::MatrixXd>& h, Index& bad_index) {
  has_factor_ = false;
  const Index n = n_;
  for (Index c = 0; c < n; ++c) {
    if (!h.col(c).allFinite()) {
      bad_index = first_non_finite_row(h);
      return QpInvalidReason::kNonFiniteHessian;
    }
  }
  // Up-looking Cholesky H = U'U on the upper triangle: every inner product runs down two
  // contiguous columns. A pivot below n eps max|H_ii| means H is not (numerically) definite.
  const double pivot_min =
      static_cast<double>(n) * std::numeric_limits<double>::epsilon() * h.diagonal().cwiseAbs().maxCoeff();
  for (Index j = 0; j < n; ++j) {
    auto col = chol_.col(j);
    for (Index i = 0; i < j; ++i) {
      col(i) = (h(i, j) - chol_.col(i).head(i).dot(col.head(i))) / chol_(i, i);
    }
    const double pivot = h(j, j) - col.head(j).squaredNorm();
    if (!(pivot > pivot_min)) {
      bad_index = j;
      return QpInvalidReason::kHessianNotPositiveDefinite;
    }
    col(j) = std::sqrt(pivot);
  }
  invert_factor();
  has_factor_ = true;
  return QpInvalidReason::kNone;
}

void QpSolver::invert_factor() {
  // Column c of U^-1 by back substitution against e_c; the strict lower part stays zero.
  for (Index c = 0; c < n_; ++c) {
    auto col = inv_chol_.col(c);
    col.head(c).setZero();
    col(c) = 1.0;
    for (Index k = c; k >= 0; --k) {
      col(k) /= chol_(k, k);
      col.head(k) -= col(k) * chol_.col(k).head(k);
    }
  }
}

// ------------------------------------------------------------------------------------ input

QpInvalidReason QpSolver::load(const QpProblem& p, bool reuse_factor) {
  const Index n = n_;
  if (n == 0) return QpInvalidReason::kDimensionMismatch;
  const auto matrix_fits = [n](const Eigen::MatrixXd& m, Index rows) {
    return m.rows() == rows && (m.cols() == n || rows == 0);
  };
  const auto side_fits = [](const Eigen::VectorXd& v, Index size) { return v.size() == size || v.size() == 0; };
  if ((!reuse_factor && (p.H.rows() != n || p.H.cols() != n)) || p.g.size() != n || !matrix_fits(p.A_eq, m_eq_) ||
      p.b_eq.size() != m_eq_ || !matrix_fits(p.A, m_in_) || !side_fits(p.l, m_in_) || !side_fits(p.u, m_in_) ||
      !side_fits(p.lb, n) || !side_fits(p.ub, n)) {
    return QpInvalidReason::kDimensionMismatch;
  }

  if (!reuse_factor) {
    const QpInvalidReason reason = factorize(p.H, invalid_index_);
    if (reason != QpInvalidReason::kNone) return reason;
  } else if (!has_factor_) {
    return QpInvalidReason::kMissingHessianFactor;
  }

  if (!p.g.allFinite()) {
    invalid_index_ = first_non_finite_row(p.g);
    return QpInvalidReason::kNonFiniteGradient;
  }
  g_ = p.g;

  const double big = settings_.infinity;
  const double tol = settings_.feasibility_tolerance;
  constexpr double kTiny = std::numeric_limits<double>::min();
  null_row_infeasible_ = false;

  if (m_eq_ > 0) {
    if (!p.A_eq.allFinite()) {
      invalid_index_ = first_non_finite_row(p.A_eq);
      return QpInvalidReason::kNonFiniteEqualityRows;
    }
    if (!p.b_eq.allFinite()) {
      invalid_index_ = first_non_finite_row(p.b_eq);
      return QpInvalidReason::kNonFiniteEqualityTarget;
    }
    rows_.leftCols(m_eq_) = p.A_eq.transpose();
  }
  for (Index k = 0; k < m_eq_; ++k) {
    const double norm = rows_.col(k).norm();
    if (norm > kTiny) {
      const double scale = 1.0 / norm;
      rows_.col(k) *= scale;
      row_scale_(k) = scale;
      lower_(k) = upper_(k) = p.b_eq(k) * scale;
    } else {
      // 0 = b: skipped as linearly dependent, its consistency decided here.
      row_scale_(k) = 0.0;
      lower_(k) = upper_(k) = 0.0;
      null_row_infeasible_ |= std::abs(p.b_eq(k)) > tol;
    }
  }

  if (m_in_ > 0) {
    if (!p.A.allFinite()) {
      invalid_index_ = first_non_finite_row(p.A);
      return QpInvalidReason::kNonFiniteInequalityRows;
    }
    rows_.middleCols(m_eq_, m_in_) = p.A.transpose();
  }
  const bool has_l = p.l.size() > 0;
  const bool has_u = p.u.size() > 0;
  for (Index i = 0; i < m_in_; ++i) {
    const Index k = m_eq_ + i;
    const double lo = has_l ? p.l(i) : -kInf;
    const double hi = has_u ? p.u(i) : kInf;
    if (std::isnan(lo) || std::isnan(hi) || lo == kInf || hi == -kInf) {
      invalid_index_ = i;
      return QpInvalidReason::kInvalidRowBound;
    }
    if (lo > hi) {
      invalid_index_ = i;
      return QpInvalidReason::kRowBoundsInverted;
    }
    const double norm = rows_.col(k).norm();
    if (norm > kTiny) {
      const double scale = 1.0 / norm;
      rows_.col(k) *= scale;
      row_scale_(k) = scale;
      lower_(k) = lo <= -big ? -kInf : lo * scale;
      upper_(k) = hi >= big ? kInf : hi * scale;
    } else {
      // l <= 0 <= u: never active.
      row_scale_(k) = 0.0;
      lower_(k) = -kInf;
      upper_(k) = kInf;
      null_row_infeasible_ |= (lo > -big && lo > tol) || (hi < big && hi < -tol);
    }
  }

  const bool has_lb = p.lb.size() > 0;
  const bool has_ub = p.ub.size() > 0;
  for (Index j = 0; j < n; ++j) {
    const double lo = has_lb ? p.lb(j) : -kInf;
    const double hi = has_ub ? p.ub(j) : kInf;
    if (std::isnan(lo) || std::isnan(hi) || lo == kInf || hi == -kInf) {
      invalid_index_ = j;
      return QpInvalidReason::kInvalidVariableBound;
    }
    if (lo > hi) {
      invalid_index_ = j;
      return QpInvalidReason::kVariableBoundsInverted;
    }
    lower_(m_rows_ + j) = lo <= -big ? -kInf : lo;
    upper_(m_rows_ + j) = hi >= big ? kInf : hi;
  }
  return QpInvalidReason::kNone;
}

// ------------------------------------------------------------------------------------ solve

QpStatus QpSolver::solve(const QpProblem& problem, const QpSolveOptions& options) {
  iterations_ = 0;
  invalid_index_ = -1;
  const QpInvalidReason reason = load(problem, options.reuse_hessian_factor);
  if (reason != QpInvalidReason::kNone) return finish_invalid(reason, invalid_index_);
  invalid_reason_ = QpInvalidReason::kNone;

  start_working_set(options.warm_start);

  // Equalities skipped as dependent must hold at the point that satisfies the independent ones.
  bool consistent = !null_row_infeasible_;
  const double base = 1.0 + x_.cwiseAbs().maxCoeff();
  for (Index k = 0; k < m_eq_ && consistent; ++k) {
    if (sign_[static_cast<std::size_t>(k)] != 0) continue;
    const double target = lower_(k);
    consistent = std::abs(rows_.col(k).dot(x_) - target) <= settings_.feasibility_tolerance * (base + std::abs(target));
  }

  QpStatus status = QpStatus::kInfeasible;
  if (consistent) {
    const int max_iterations = settings_.max_iterations > 0
                                   ? settings_.max_iterations
                                   : static_cast<int>(10 * (n_ + m_eq_ + m_in_) + 10);
    status = iterate(max_iterations);
  }

  publish();
  if (!x_.allFinite() || !std::isfinite(objective_) || !y_eq_.allFinite() || !y_row_.allFinite() ||
      !y_bound_.allFinite()) {
    status = QpStatus::kNumericalError;
    x_.setZero();
    y_eq_.setZero();
    y_row_.setZero();
    y_bound_.setZero();
    objective_ = 0.0;
  }
  status_ = status;
  return status;
}

QpStatus QpSolver::finish_invalid(QpInvalidReason reason, Index index) {
  status_ = QpStatus::kInvalidInput;
  invalid_reason_ = reason;
  invalid_index_ = index;
  q_ = 0;
  x_.setZero();
  y_eq_.setZero();
  y_row_.setZero();
  y_bound_.setZero();
  objective_ = 0.0;
  return status_;
}

void QpSolver::start_working_set(bool warm) {
  j_ = inv_chol_;
  q_ = 0;
  std::fill(sign_.begin(), sign_.end(), std::int8_t{0});
  for (Index k = 0; k < m_eq_; ++k) add_warm_constraint(k, +1);

  if (warm) {
    // The guess enters as equalities (no step needed: x is recomputed below); absent sides and
    // normals dependent on those already in are skipped.
    for (Index i = 0; i < m_in_; ++i) {
      const Index k = m_eq_ + i;
      const QpActiveSide side = row_sides_[static_cast<std::size_t>(i)];
      if (side == QpActiveSide::kLower && lower_(k) > -kInf) add_warm_constraint(k, +1);
      if (side == QpActiveSide::kUpper && upper_(k) < kInf) add_warm_constraint(k, -1);
    }
    for (Index j = 0; j < n_; ++j) {
      const Index k = m_rows_ + j;
      const QpActiveSide side = bound_sides_[static_cast<std::size_t>(j)];
      if (side == QpActiveSide::kLower && lower_(k) > -kInf) add_warm_constraint(k, +1);
      if (side == QpActiveSide::kUpper && upper_(k) < kInf) add_warm_constraint(k, -1);
    }
  }
  solve_working_set();

  if (warm) {
    // The dual method needs u >= 0 on the inequalities: drop the most negative multiplier and
    // re-solve the equality-constrained problem until none is left. Ends at worst with the
    // equalities alone, the cold start.
    while (true) {
      Index worst = -1;
      double worst_u = 0.0;
      for (Index j = 0; j < q_; ++j) {
        if (active_[static_cast<std::size_t>(j)] >= m_eq_ && u_(j) < worst_u) {
          worst_u = u_(j);
          worst = j;
        }
      }
      if (worst < 0) break;
      drop_constraint(worst);
      ++iterations_;
      solve_working_set();
    }
  }
}

void QpSolver::add_warm_constraint(Index k, int sign) {
  if (q_ == n_) return;
  compute_normal_product(k, sign);
  const double outside = d_.tail(n_ - q_).squaredNorm();
  const double tol = settings_.dependence_tolerance;
  if (outside > tol * tol * d_.squaredNorm()) add_constraint(k, sign, 0.0);
}

void QpSolver::solve_working_set() {
  // With x = J y the objective is 1/2 y'y + (J'g)'y and the active constraints read R'y1 = b,
  // so y1 = R^-T b, y2 = -J2'g, and the multipliers solve R u = y1 + J1'g.
  const Index n = n_;
  const Index q = q_;
  work_.noalias() = j_.transpose() * g_;
  for (Index i = 0; i < q; ++i) {
    dir_(i) = (active_target(i) - r_.col(i).head(i).dot(dir_.head(i))) / r_(i, i);
  }
  x_.noalias() = j_.leftCols(q) * dir_.head(q);
  x_.noalias() -= j_.rightCols(n - q) * work_.tail(n - q);
  u_.head(q) = dir_.head(q) + work_.head(q);
  back_substitute(r_, q, u_);
}

void QpSolver::polish_active_constraints() {
  // A primal step moves x orthogonally to the active normals only up to roundoff, and long
  // steps (ill-conditioned H, nearly dependent normals) make the active constraints drift, enough
  // to make a parallel copy of one look violated. The minimum H-norm correction
  // dx = J1 R^-T (b - N'x) restores them (N'J1 = R'); H dx is negligible.
  const Index q = q_;
  for (Index i = 0; i < q; ++i) {
    const Index k = active_[static_cast<std::size_t>(i)];
    const double value = k < m_rows_ ? rows_.col(k).dot(x_) : x_(k - m_rows_);
    const double residual = active_target(i) - sign_[static_cast<std::size_t>(k)] * value;
    dir_(i) = (residual - r_.col(i).head(i).dot(dir_.head(i))) / r_(i, i);
  }
  x_.noalias() += j_.leftCols(q) * dir_.head(q);
}

double QpSolver::active_target(Index j) const {
  const Index k = active_[static_cast<std::size_t>(j)];
  return sign_[static_cast<std::size_t>(k)] > 0 ? lower_(k) : -upper_(k);
}

bool QpSolver::most_violated(Index& best_k, int& best_sign) {
  // Relative to |x| too: the roundoff of a'x grows with it.
  const double tol = settings_.feasibility_tolerance;
  const double base = 1.0 + x_.cwiseAbs().maxCoeff();
  double best = 0.0;
  best_k = -1;
  if (m_in_ > 0) row_values_.noalias() = rows_.middleCols(m_eq_, m_in_).transpose() * x_;
  for (Index i = 0; i < m_in_; ++i) {
    const Index k = m_eq_ + i;
    if (sign_[static_cast<std::size_t>(k)] != 0) continue;
    const double v = row_values_(i);
    const double below = lower_(k) - v;
    if (below > best && below > tol * (base + std::abs(lower_(k)))) {
      best = below;
      best_k = k;
      best_sign = +1;
    }
    const double above = v - upper_(k);
    if (above > best && above > tol * (base + std::abs(upper_(k)))) {
      best = above;
      best_k = k;
      best_sign = -1;
    }
  }
  for (Index j = 0; j < n_; ++j) {
    const Index k = m_rows_ + j;
    if (sign_[static_cast<std::size_t>(k)] != 0) continue;
    const double v = x_(j);
    const double below = lower_(k) - v;
    if (below > best && below > tol * (base + std::abs(lower_(k)))) {
      best = below;
      best_k = k;
      best_sign = +1;
    }
    const double above = v - upper_(k);
    if (above > best && above > tol * (base + std::abs(upper_(k)))) {
      best = above;
      best_k = k;
      best_sign = -1;
    }
  }
  return best_k >= 0;
}

QpStatus QpSolver::iterate(int max_iterations) {
  const Index n = n_;
  const double dependence2 = settings_.dependence_tolerance * settings_.dependence_tolerance;
  while (true) {
    // Step 1: the most violated constraint p, or optimal.
    Index p = -1;
    int sign = 0;
    if (!most_violated(p, sign)) return QpStatus::kOptimal;
    double u_p = 0.0;

    // Step 2: move (x, u) until p is satisfied, dropping the constraints whose multiplier
    // reaches zero on the way (partial steps).
    while (true) {
      if (iterations_ >= max_iterations) return QpStatus::kIterationLimit;
      const Index q = q_;
      compute_normal_product(p, sign);
      const double outside = d_.tail(n - q).squaredNorm();  // = z'n, z = J2 d2
      const bool primal_step = outside > dependence2 * d_.squaredNorm();

      dir_.head(q) = d_.head(q);
      back_substitute(r_, q, dir_);
      // t1: largest dual step keeping the inequality multipliers >= 0. Entries of r that are
      // roundoff next to the largest one do not block.
      const double r_floor = q > 0 ? 1e-12 * dir_.head(q).cwiseAbs().maxCoeff() : 0.0;
      double t1 = kInf;
      Index blocking = -1;
      for (Index j = 0; j < q; ++j) {
        if (active_[static_cast<std::size_t>(j)] < m_eq_ || !(dir_(j) > r_floor)) continue;
        const double ratio = u_(j) / dir_(j);
        if (ratio < t1) {
          t1 = ratio;
          blocking = j;
        }
      }
      // p is a nonpositive combination of active normals: no point satisfies them all.
      if (!primal_step && blocking < 0) return QpStatus::kInfeasible;
      ++iterations_;

      double t = t1;
      bool full_step = false;
      if (primal_step) {
        const double t2 = std::max(-slack(p, sign) / outside, 0.0);
        if (t2 <= t1) {
          t = t2;
          full_step = true;
        }
        x_.noalias() += j_.rightCols(n - q) * (t * d_.tail(n - q));
      }
      u_.head(q) -= t * dir_.head(q);
      for (Index j = 0; j < q; ++j) {
        if (active_[static_cast<std::size_t>(j)] >= m_eq_ && u_(j) < 0.0) u_(j) = 0.0;
      }
      u_p += t;
      if (full_step) {
        add_constraint(p, sign, u_p);  // d_ is still J'n for the current J
        polish_active_constraints();
        break;
      }
      drop_constraint(blocking);
    }
  }
}

void QpSolver::compute_normal_product(Index k, int sign) {
  if (k < m_rows_) {
    d_.noalias() = j_.transpose() * rows_.col(k);
    if (sign < 0) d_ = -d_;
  } else if (sign > 0) {
    d_ = j_.row(k - m_rows_).transpose();  // a bound's normal is a unit vector
  } else {
    d_ = -j_.row(k - m_rows_).transpose();
  }
}

double QpSolver::slack(Index k, int sign) const {
  const double v = k < m_rows_ ? rows_.col(k).dot(x_) : x_(k - m_rows_);
  return sign > 0 ? v - lower_(k) : upper_(k) - v;
}

void QpSolver::add_constraint(Index k, int sign, double multiplier) {
  // Rotate d2 onto its first entry (bottom up), applying each rotation to J: the columns of J2
  // beyond q stay orthogonal to every active normal, and [d1; |d2|] becomes column q of R.
  const Index q = q_;
  for (Index i = n_ - 1; i > q; --i) {
    const double b = d_(i);
    if (b == 0.0) continue;
    const double a = d_(i - 1);
    const double h = std::sqrt(a * a + b * b);
    d_(i - 1) = h;
    d_(i) = 0.0;
    rotate_columns(j_, i - 1, i, a / h, b / h);
  }
  r_.col(q).head(q + 1) = d_.head(q + 1);
  active_[static_cast<std::size_t>(q)] = k;
  u_(q) = multiplier;
  sign_[static_cast<std::size_t>(k)] = static_cast<std::int8_t>(sign);
  ++q_;
}

void QpSolver::drop_constraint(Index j) {
  // Removing column j of R leaves it upper Hessenberg from column j on; rotations of the row
  // pairs (t, t+1) restore the triangle and are mirrored on the columns of J.
  const Index q = q_;
  sign_[static_cast<std::size_t>(active_[static_cast<std::size_t>(j)])] = 0;
  for (Index t = j; t + 1 < q; ++t) {
    active_[static_cast<std::size_t>(t)] = active_[static_cast<std::size_t>(t + 1)];
    u_(t) = u_(t + 1);
    r_.col(t).head(t + 2) = r_.col(t + 1).head(t + 2);
  }
  for (Index t = j; t + 1 < q; ++t) {
    const double b = r_(t + 1, t);
    if (b == 0.0) continue;
    const double a = r_(t, t);
    const double h = std::sqrt(a * a + b * b);
    const double c = a / h;
    const double s = b / h;
    r_(t, t) = h;
    r_(t + 1, t) = 0.0;
    for (Index col = t + 1; col + 1 < q; ++col) {
      const double ra = r_(t, col);
      const double rb = r_(t + 1, col);
      r_(t, col) = c * ra + s * rb;
      r_(t + 1, col) = c * rb - s * ra;
    }
    rotate_columns(j_, t, t + 1, c, s);
  }
  --q_;
}

void QpSolver::publish() {
  // Paper: Hx + g = N u, u >= 0; here n_k = sign a_k / |a_k|, hence y_k = -sign u / |a_k|.
  y_eq_.setZero();
  y_row_.setZero();
  y_bound_.setZero();
  for (Index j = 0; j < q_; ++j) {
    const Index k = active_[static_cast<std::size_t>(j)];
    const double y = -u_(j) * sign_[static_cast<std::size_t>(k)];
    if (k < m_eq_) {
      y_eq_(k) = y * row_scale_(k);
    } else if (k < m_rows_) {
      y_row_(k - m_eq_) = y * row_scale_(k);
    } else {
      y_bound_(k - m_rows_) = y;
    }
  }
  for (Index i = 0; i < m_in_; ++i) {
    row_sides_[static_cast<std::size_t>(i)] = side_of(sign_[static_cast<std::size_t>(m_eq_ + i)]);
  }
  for (Index j = 0; j < n_; ++j) {
    bound_sides_[static_cast<std::size_t>(j)] = side_of(sign_[static_cast<std::size_t>(m_rows_ + j)]);
  }
  // 1/2 |U x|^2 + g'x with H = U'U.
  work_.setZero();
  for (Index c = 0; c < n_; ++c) work_.head(c + 1) += x_(c) * chol_.col(c).head(c + 1);
  objective_ = 0.5 * work_.squaredNorm() + g_.dot(x_);
}

bool QpSolver::set_active_set(std::span<const QpActiveSide> rows, std::span<const QpActiveSide> bounds) {
  if (static_cast<Index>(rows.size()) != m_in_ || static_cast<Index>(bounds.size()) != n_) return false;
  std::copy(rows.begin(), rows.end(), row_sides_.begin());
  std::copy(bounds.begin(), bounds.end(), bound_sides_.begin());
  return true;
}

}  // namespace phri
