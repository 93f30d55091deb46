// Goldfarb-Idnani dual active-set method. Notation of the paper: H = L L', the active normals N
// (q columns), J = L^-T Q and R upper triangular with Q' L^-1 N = [R; 0]; J1 = first q columns of
// J, J2 = the rest. For a constraint n'x >= b entering the active set, d = J'n, the primal step
// direction is z = J2 d2 and the dual one r = R^-1 d1 (Section 3 of the paper). L is chol_ and
// the initial J = L^-T is inv_chol_, both computed once per factorisation.
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

using Index = Eigen::Index;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMax = std::numeric_limits<double>::max();

// Small dense kernels on raw columns. The sizes change at run time and are mostly tiny (the
// controller's n = 7), where plain inlined loops beat the dispatch of Eigen's general products;
// from kLargeRows rows on, Eigen's blocked matrix-vector products win.
constexpr Index kLargeRows = 16;

// Four partial sums: no loop-carried dependence on a single accumulator.
[[gnu::always_inline]] inline double dot(const double* __restrict a, const double* __restrict b, Index n) {
  double s0 = 0.0;
  double s1 = 0.0;
  double s2 = 0.0;
  double s3 = 0.0;
  Index i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += a[i] * b[i];
    s1 += a[i + 1] * b[i + 1];
    s2 += a[i + 2] * b[i + 2];
    s3 += a[i + 3] * b[i + 3];
  }
  for (; i < n; ++i) s0 += a[i] * b[i];
  return (s0 + s1) + (s2 + s3);
}

// y += alpha x
[[gnu::always_inline]] inline void axpy(double alpha, const double* __restrict x, double* __restrict y, Index n) {
  for (Index i = 0; i < n; ++i) y[i] += alpha * x[i];
}

using ConstColumns = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

// out[c] = M(:, c)' v, M with `rows` rows, `cols` columns, leading dimension ld.
void columns_dot(const double* m, Index ld, Index rows, Index cols, const double* v, double* out) {
  if (rows >= kLargeRows) {
    Eigen::Map<Eigen::VectorXd>(out, cols).noalias() =
        ConstColumns(m, rows, cols, Eigen::OuterStride<>(ld)).transpose() * Eigen::Map<const Eigen::VectorXd>(v, rows);
    return;
  }
  for (Index c = 0; c < cols; ++c) out[c] = dot(m + c * ld, v, rows);
}

// y += M coef
void columns_axpy(const double* m, Index ld, Index rows, Index cols, const double* coef, double* y) {
  if (rows >= kLargeRows) {
    Eigen::Map<Eigen::VectorXd>(y, rows).noalias() +=
        ConstColumns(m, rows, cols, Eigen::OuterStride<>(ld)) * Eigen::Map<const Eigen::VectorXd>(coef, cols);
    return;
  }
  for (Index c = 0; c < cols; ++c) axpy(coef[c], m + c * ld, y, rows);
}

bool all_finite(const double* p, Index n) {
  bool ok = true;
  for (Index i = 0; i < n; ++i) ok &= std::abs(p[i]) <= kMax;
  return ok;
}

// v[0..q) <- R^-1 v[0..q), R the leading q x q block of an upper-triangular matrix (leading
// dimension ld), column by column.
void back_substitute(const double* r, Index ld, Index q, double* v) {
  for (Index i = q - 1; i >= 0; --i) {
    v[i] /= r[i + i * ld];
    axpy(-v[i], r + i * ld, v, i);
  }
}

// y[0..q) <- R^-T b[0..q); y may alias b.
void forward_substitute_transposed(const double* r, Index ld, Index q, const double* b, double* y) {
  for (Index i = 0; i < q; ++i) y[i] = (b[i] - dot(r + i * ld, y, i)) / r[i + i * ld];
}

// Columns a <- c a + s b and b <- c b - s a.
void rotate_columns(Eigen::MatrixXd& m, Index ia, Index ib, double c, double s) {
  double* __restrict a = m.col(ia).data();
  double* __restrict b = m.col(ib).data();
  const Index rows = m.rows();
  for (Index t = 0; t < rows; ++t) {
    const double va = a[t];
    const double vb = b[t];
    a[t] = c * va + s * vb;
    b[t] = c * vb - s * va;
  }
}

template <typename Matrix>
Index first_non_finite_row(const Matrix& m) {
  for (Index i = 0; i < m.rows(); ++i) {
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
  row_values_.setZero(m_in_);
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
    if (!all_finite(factor_l.col(c).data() + c, n_ - c) || !(factor_l(c, c) > 0.0)) {
      return QpInvalidReason::kInvalidHessianFactor;
    }
  }
  chol_.triangularView<Eigen::Lower>() = factor_l;
  invert_factor();
  has_factor_ = true;
  return QpInvalidReason::kNone;
}

QpInvalidReason QpSolver::factorize(const Eigen::Ref<const Eigen::MatrixXd>& h, Index& bad_index) {
  has_factor_ = false;
  const Index n = n_;
  bool finite = true;
  double max_diagonal = 0.0;
  double* l = chol_.data();
  for (Index c = 0; c < n; ++c) {
    const double* hc = h.col(c).data();
    finite &= all_finite(hc, n);
    max_diagonal = std::max(max_diagonal, std::abs(hc[c]));
    for (Index i = c; i < n; ++i) l[i + c * n] = hc[i];
  }
  if (!finite) {
    bad_index = first_non_finite_row(h);
    return QpInvalidReason::kNonFiniteHessian;
  }
  // Right-looking Cholesky H = L L' on the lower triangle: each step scales a column and updates
  // the trailing columns with contiguous axpys. A pivot below n eps max|H_ii| means H is not
  // (numerically) positive definite.
  const double pivot_min = static_cast<double>(n) * std::numeric_limits<double>::epsilon() * max_diagonal;
  for (Index k = 0; k < n; ++k) {
    double* lk = l + k * n;
    const double pivot = lk[k];
    if (!(pivot > pivot_min)) {
      bad_index = k;
      return QpInvalidReason::kHessianNotPositiveDefinite;
    }
    lk[k] = std::sqrt(pivot);
    const double inv = 1.0 / lk[k];
    for (Index i = k + 1; i < n; ++i) lk[i] *= inv;
    for (Index j = k + 1; j < n; ++j) axpy(-lk[j], lk + j, l + j * n + j, n - j);
  }
  invert_factor();
  has_factor_ = true;
  return QpInvalidReason::kNone;
}

void QpSolver::invert_factor() {
  // Column c of L^-1 by forward substitution against e_c, written transposed as row c of
  // J = L^-T; the strict lower part of J stays zero.
  const Index n = n_;
  const double* l = chol_.data();
  double* j = inv_chol_.data();
  double* inv_diag = work_.data();
  double* col = d_.data();
  for (Index k = 0; k < n; ++k) inv_diag[k] = 1.0 / l[k + k * n];
  for (Index c = 0; c < n; ++c) {
    for (Index k = c; k < n; ++k) col[k] = 0.0;
    col[c] = 1.0;
    for (Index k = c; k < n; ++k) {
      col[k] *= inv_diag[k];
      axpy(-col[k], l + k * n + k + 1, col + k + 1, n - k - 1);
    }
    for (Index k = c; k < n; ++k) j[c + k * n] = col[k];
  }
}

// ------------------------------------------------------------------------------------ input

// Scales row k (a column of rows_) to unit length. Returns false when it holds NaN or Inf.
bool QpSolver::normalize_row(Index k) {
  double* a = rows_.col(k).data();
  double squared = dot(a, a, n_);
  if (!(squared >= std::numeric_limits<double>::min() && squared <= kMax)) {
    // Rare: non-finite, zero, or so large or small that the squares leave the double range.
    if (!all_finite(a, n_)) return false;
    squared = rows_.col(k).stableNorm();
    squared *= squared;
  }
  if (squared > 0.0 && std::isfinite(squared)) {
    const double scale = 1.0 / std::sqrt(squared);
    for (Index i = 0; i < n_; ++i) a[i] *= scale;
    row_scale_(k) = scale;
  } else {
    row_scale_(k) = 0.0;  // an all-zero row (or one beyond 1e154 that cannot be scaled)
  }
  return true;
}

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

  if (!all_finite(p.g.data(), n)) {
    invalid_index_ = first_non_finite_row(p.g);
    return QpInvalidReason::kNonFiniteGradient;
  }
  g_ = p.g;

  const double big = settings_.infinity;
  const double tol = settings_.feasibility_tolerance;
  null_row_infeasible_ = false;

  if (m_eq_ > 0) {
    if (!all_finite(p.b_eq.data(), m_eq_)) {
      invalid_index_ = first_non_finite_row(p.b_eq);
      return QpInvalidReason::kNonFiniteEqualityTarget;
    }
    rows_.leftCols(m_eq_) = p.A_eq.transpose();
  }
  for (Index k = 0; k < m_eq_; ++k) {
    if (!normalize_row(k)) {
      invalid_index_ = k;
      return QpInvalidReason::kNonFiniteEqualityRows;
    }
    // An all-zero row reads 0 = b: skipped as dependent, its consistency decided here.
    lower_(k) = upper_(k) = p.b_eq(k) * row_scale_(k);
    null_row_infeasible_ |= row_scale_(k) == 0.0 && std::abs(p.b_eq(k)) > tol;
  }

  if (m_in_ > 0) rows_.middleCols(m_eq_, m_in_) = p.A.transpose();
  const bool has_l = p.l.size() > 0;
  const bool has_u = p.u.size() > 0;
  for (Index i = 0; i < m_in_; ++i) {
    const Index k = m_eq_ + i;
    if (!normalize_row(k)) {
      invalid_index_ = i;
      return QpInvalidReason::kNonFiniteInequalityRows;
    }
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
    const double scale = row_scale_(k);
    if (scale > 0.0) {
      lower_(k) = lo <= -big ? -kInf : lo * scale;
      upper_(k) = hi >= big ? kInf : hi * scale;
    } else {
      // An all-zero row: l <= 0 <= u or nothing, never active.
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
    const double value = dot(rows_.col(k).data(), x_.data(), n_);
    consistent = std::abs(value - target) <= settings_.feasibility_tolerance * (base + std::abs(target));
  }

  QpStatus status = QpStatus::kInfeasible;
  if (consistent) {
    const int max_iterations = settings_.max_iterations > 0
                                   ? settings_.max_iterations
                                   : static_cast<int>(10 * (n_ + m_eq_ + m_in_) + 10);
    status = iterate(max_iterations);
  }

  publish();
  if (!all_finite(x_.data(), n_) || !std::isfinite(objective_) || !y_eq_.allFinite() || !y_row_.allFinite() ||
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
  const double outside = dot(d_.data() + q_, d_.data() + q_, n_ - q_);
  const double tol = settings_.dependence_tolerance;
  if (outside > tol * tol * dot(d_.data(), d_.data(), n_)) add_constraint(k, sign, 0.0);
}

void QpSolver::solve_working_set() {
  // With x = J y the objective is 1/2 y'y + (J'g)'y and the active constraints read R'y1 = b,
  // so y1 = R^-T b, y2 = -J2'g, and the multipliers solve R u = y1 + J1'g.
  const Index n = n_;
  const Index q = q_;
  const double* j = j_.data();
  double* c = work_.data();
  double* y = dir_.data();
  columns_dot(j, n, n, n, g_.data(), c);
  for (Index i = 0; i < q; ++i) y[i] = active_target(i);
  forward_substitute_transposed(r_.data(), n, q, y, y);
  for (Index i = q; i < n; ++i) y[i] = -c[i];
  x_.setZero();
  columns_axpy(j, n, n, n, y, x_.data());
  for (Index i = 0; i < q; ++i) u_(i) = y[i] + c[i];
  back_substitute(r_.data(), n, q, u_.data());
}

void QpSolver::polish_active_constraints() {
  // A primal step moves x orthogonally to the active normals only up to roundoff, and long
  // steps (ill-conditioned H, nearly dependent normals) make the active constraints drift, enough
  // to make a parallel copy of one look violated. The minimum H-norm correction
  // dx = J1 R^-T (b - N'x) restores them (N'J1 = R'); H dx is negligible.
  const Index n = n_;
  const Index q = q_;
  double* y = dir_.data();
  for (Index i = 0; i < q; ++i) {
    const Index k = active_[static_cast<std::size_t>(i)];
    const double value = k < m_rows_ ? dot(rows_.col(k).data(), x_.data(), n) : x_(k - m_rows_);
    y[i] = active_target(i) - sign_[static_cast<std::size_t>(k)] * value;
  }
  forward_substitute_transposed(r_.data(), n, q, y, y);
  columns_axpy(j_.data(), n, n, q, y, x_.data());
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
  const auto consider = [&](Index k, double value) {
    const double below = lower_(k) - value;
    if (below > best && below > tol * (base + std::abs(lower_(k)))) {
      best = below;
      best_k = k;
      best_sign = +1;
    }
    const double above = value - upper_(k);
    if (above > best && above > tol * (base + std::abs(upper_(k)))) {
      best = above;
      best_k = k;
      best_sign = -1;
    }
  };
  if (n_ >= kLargeRows) {
    columns_dot(rows_.col(m_eq_).data(), n_, n_, m_in_, x_.data(), row_values_.data());
    for (Index i = 0; i < m_in_; ++i) {
      if (sign_[static_cast<std::size_t>(m_eq_ + i)] == 0) consider(m_eq_ + i, row_values_(i));
    }
  } else {
    for (Index k = m_eq_; k < m_rows_; ++k) {
      if (sign_[static_cast<std::size_t>(k)] == 0) consider(k, dot(rows_.col(k).data(), x_.data(), n_));
    }
  }
  for (Index j = 0; j < n_; ++j) {
    if (sign_[static_cast<std::size_t>(m_rows_ + j)] == 0) consider(m_rows_ + j, x_(j));
  }
  return best_k >= 0;
}

QpStatus QpSolver::iterate(int max_iterations) {
  const Index n = n_;
  const double dependence2 = settings_.dependence_tolerance * settings_.dependence_tolerance;
  double* d = d_.data();
  double* r = dir_.data();
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
      const double outside = dot(d + q, d + q, n - q);  // = z'n, z = J2 d2
      const bool primal_step = outside > dependence2 * (outside + dot(d, d, q));

      // t1: largest dual step keeping the inequality multipliers >= 0. Entries of r that are
      // roundoff next to the largest one do not block.
      for (Index j = 0; j < q; ++j) r[j] = d[j];
      back_substitute(r_.data(), n, q, r);
      double r_max = 0.0;
      for (Index j = 0; j < q; ++j) r_max = std::max(r_max, std::abs(r[j]));
      const double r_floor = 1e-12 * r_max;
      double t1 = kInf;
      Index blocking = -1;
      for (Index j = 0; j < q; ++j) {
        if (active_[static_cast<std::size_t>(j)] < m_eq_ || !(r[j] > r_floor)) continue;
        const double ratio = u_(j) / r[j];
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
        double* step = work_.data();
        for (Index j = q; j < n; ++j) step[j] = t * d[j];
        columns_axpy(j_.col(q).data(), n, n, n - q, step + q, x_.data());
      }
      for (Index j = 0; j < q; ++j) {
        u_(j) -= t * r[j];
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
  const Index n = n_;
  double* d = d_.data();
  const double* j = j_.data();
  if (k < m_rows_) {
    columns_dot(j, n, n, n, rows_.col(k).data(), d);
    if (sign < 0) {
      for (Index i = 0; i < n; ++i) d[i] = -d[i];
    }
  } else {
    // A bound's normal is a unit vector: d is a row of J.
    const Index b = k - m_rows_;
    for (Index i = 0; i < n; ++i) d[i] = sign * j[b + i * n];
  }
}

double QpSolver::slack(Index k, int sign) const {
  const double v = k < m_rows_ ? dot(rows_.col(k).data(), x_.data(), n_) : x_(k - m_rows_);
  return sign > 0 ? v - lower_(k) : upper_(k) - v;
}

void QpSolver::add_constraint(Index k, int sign, double multiplier) {
  // Rotate d2 onto its first entry (bottom up), applying each rotation to J: the columns of J2
  // beyond q stay orthogonal to every active normal, and [d1; |d2|] becomes column q of R.
  // The rotated values are the norms of the trailing parts of d, so all square roots are taken
  // up front instead of one after the other along the chain of rotations.
  const Index n = n_;
  const Index q = q_;
  double* d = d_.data();
  double* norms = work_.data();
  double sum = 0.0;
  for (Index i = n - 1; i >= q; --i) {
    sum += d[i] * d[i];
    norms[i] = sum;
  }
  for (Index i = q; i < n; ++i) norms[i] = std::sqrt(norms[i]);
  double current = n > q ? d[n - 1] : 0.0;  // value at position i after the rotations below it
  for (Index i = n - 1; i > q; --i) {
    if (current == 0.0) {
      current = d[i - 1];
      continue;
    }
    const double inv = 1.0 / norms[i - 1];
    rotate_columns(j_, i - 1, i, d[i - 1] * inv, current * inv);
    current = norms[i - 1];
  }
  double* r_col = r_.col(q).data();
  for (Index i = 0; i < q; ++i) r_col[i] = d[i];
  r_col[q] = current;
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
  // 1/2 |L'x|^2 + g'x with H = L L'.
  double half_xhx = 0.0;
  for (Index c = 0; c < n_; ++c) {
    const double w = dot(chol_.col(c).data() + c, x_.data() + c, n_ - c);
    half_xhx += w * w;
  }
  objective_ = 0.5 * half_xhx + dot(g_.data(), x_.data(), n_);
}

bool QpSolver::set_active_set(std::span<const QpActiveSide> rows, std::span<const QpActiveSide> bounds) {
  if (static_cast<Index>(rows.size()) != m_in_ || static_cast<Index>(bounds.size()) != n_) return false;
  std::copy(rows.begin(), rows.end(), row_sides_.begin());
  std::copy(bounds.begin(), bounds.end(), bound_sides_.begin());
  return true;
}

}  // namespace phri
