// Goldfarb-Idnani dual active-set method. Notation of the paper: H = L L', the active normals N
// (q columns), J = L^-T Q and R upper triangular with Q' L^-1 N = [R; 0]; J1 = first q columns of
// J, J2 = the rest. For a constraint n'x >= b entering the active set, d = J'n, the primal step
// direction is z = J2 d2 and the dual one r = R^-1 d1 (Section 3 of the paper). L is chol_ and
// the initial J = L^-T is inv_chol_, formed from L once per factorisation and only when a solve
// needs it: a solve that starts and ends with no constraint active (most of the controller's
// ticks) takes x = -H^-1 g from L's two triangular solves and never forms J.
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

// sum_i term(i) for i in [0, n), in four partial sums: no loop-carried dependence on a single
// accumulator, so the compiler vectorises it.
template <class Term>
[[gnu::always_inline]] inline double sum4(Index n, Term term) {
  double s0 = 0.0;
  double s1 = 0.0;
  double s2 = 0.0;
  double s3 = 0.0;
  Index i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += term(i);
    s1 += term(i + 1);
    s2 += term(i + 2);
    s3 += term(i + 3);
  }
  for (; i < n; ++i) s0 += term(i);
  return (s0 + s1) + (s2 + s3);
}

[[gnu::always_inline]] inline double dot(const double* __restrict a, const double* __restrict b, Index n) {
  return sum4(n, [a, b](Index i) { return a[i] * b[i]; });
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

// x * 0 is 0 for finite x and NaN otherwise, and a sum of zeros and NaNs is NaN in any order:
// four partial sums let the compiler vectorise the check.
[[gnu::always_inline]] inline bool all_finite(const double* __restrict p, Index n) {
  return sum4(n, [p](Index i) { return p[i] * 0.0; }) == 0.0;
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

// The sign a warm-start side enters with (+1 lower, -1 upper), or 0 when it is inactive or absent.
int warm_sign(QpActiveSide side, double lower, double upper) {
  if (side == QpActiveSide::kLower && lower > -kInf) return +1;
  if (side == QpActiveSide::kUpper && upper < kInf) return -1;
  return 0;
}

// Cholesky factor L of an n x n matrix, n <= kSmall: H is padded with the identity
// to kSmall x kSmall (the padding factors to itself) so that the compile-time loop bounds let
// the compiler unroll everything. It runs as L D L' (W = L D column by column), which leaves
// one division per column on the critical path instead of a square root and a division; the
// square roots of D are taken afterwards, all at once. Returns the first pivot at or below
// pivot_min, or -1.
constexpr Index kSmall = 8;

Index factor_small(const double* h, Index ld, Index n, double pivot_min, double* l_out) {
  constexpr int N = kSmall;
  double w[N][N];  // w[column][row]
  double inv_d[N];
#pragma GCC unroll 8
  for (int c = 0; c < N; ++c) {
#pragma GCC unroll 8
    for (int r = 0; r < N; ++r) w[c][r] = (c < n && r < n) ? h[r + c * ld] : (r == c ? 1.0 : 0.0);
  }
  // Column j: H(:, j) - sum_{k<j} L(j, k) W(:, k), L(j, k) = W(j, k) / D_k; rows above the
  // diagonal are not needed and cleared.
#pragma GCC unroll 8
  for (int j = 0; j < N; ++j) {
#pragma GCC unroll 8
    for (int k = 0; k < j; ++k) {
      const double f = w[k][j] * inv_d[k];
#pragma GCC unroll 8
      for (int r = 0; r < N; ++r) w[j][r] -= f * w[k][r];
    }
#pragma GCC unroll 8
    for (int r = 0; r < j; ++r) w[j][r] = 0.0;
    if (j < n && !(w[j][j] > pivot_min)) return j;  // the padding's unit pivots are not H's
    inv_d[j] = 1.0 / w[j][j];
  }
  double scale[N];  // D^-1/2
#pragma GCC unroll 8
  for (int k = 0; k < N; ++k) scale[k] = std::sqrt(inv_d[k]);
  for (Index c = 0; c < n; ++c) {
    for (Index r = 0; r < n; ++r) l_out[r + c * n] = w[c][r] * scale[c];
  }
  return -1;
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
  has_inverse_ = false;
  j_formed_ = false;

  rows_.setZero(n_, m_rows_);
  row_scale_.setZero(m_rows_);
  row_peak_.setZero(std::max(m_eq_, m_in_));
  row_values_.setZero(m_in_);
  live_rows_.assign(static_cast<std::size_t>(m_in_), 0);
  live_row_count_ = 0;
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
  has_factor_ = true;
  has_inverse_ = false;
  return QpInvalidReason::kNone;
}

QpInvalidReason QpSolver::factorize(const Eigen::Ref<const Eigen::MatrixXd>& h, Index& bad_index) {
  has_factor_ = false;
  has_inverse_ = false;
  const Index n = n_;
  bool finite = true;
  double max_diagonal = 0.0;
  double* l = chol_.data();
  for (Index c = 0; c < n; ++c) {
    finite &= all_finite(h.col(c).data(), n);
    max_diagonal = std::max(max_diagonal, std::abs(h(c, c)));
  }
  if (!finite) {
    bad_index = first_non_finite_row(h);
    return QpInvalidReason::kNonFiniteHessian;
  }
  // A pivot below n eps max|H_ii| means H is not (numerically) positive definite.
  const double pivot_min = static_cast<double>(n) * std::numeric_limits<double>::epsilon() * max_diagonal;
  if (n <= kSmall) {
    bad_index = factor_small(h.data(), h.outerStride(), n, pivot_min, l);
    if (bad_index >= 0) return QpInvalidReason::kHessianNotPositiveDefinite;
    has_factor_ = true;
    return QpInvalidReason::kNone;
  }
  // Left-looking Cholesky H = L L' on the lower triangle: column j is H(j:n, j) minus
  // L(j, k) L(j:n, k) for the columns k < j, then scaled. Each column is updated by axpys of one
  // length (no store-to-load stalls on partly rewritten vectors).
  for (Index c = 0; c < n; ++c) {
    for (Index i = c; i < n; ++i) l[i + c * n] = h(i, c);
  }
  for (Index j = 0; j < n; ++j) {
    double* lj = l + j * n;
    for (Index k = 0; k < j; ++k) axpy(-l[j + k * n], l + k * n + j, lj + j, n - j);
    const double pivot = lj[j];
    if (!(pivot > pivot_min)) {
      bad_index = j;
      return QpInvalidReason::kHessianNotPositiveDefinite;
    }
    const double inv = 1.0 / std::sqrt(pivot);
    for (Index i = j; i < n; ++i) lj[i] *= inv;
  }
  has_factor_ = true;
  return QpInvalidReason::kNone;
}

void QpSolver::invert_factor() {
  // From L L^-1 = I, row k of L^-1, i.e. column k of J = L^-T, is
  // (e_k - sum_{i<k} L(k, i) J(:, i)) / L(k, k). J is upper triangular, so every axpy may run over
  // rows 0..k (one length per column, no store-to-load stalls); the strict lower part stays zero.
  const Index n = n_;
  const double* l = chol_.data();
  double* j = inv_chol_.data();
  for (Index k = 0; k < n; ++k) {
    double* col = j + k * n;
    for (Index r = 0; r < k; ++r) col[r] = 0.0;
    col[k] = 1.0;
    for (Index i = 0; i < k; ++i) axpy(-l[k + i * n], j + i * n, col, k + 1);
    const double inv = 1.0 / l[k + k * n];
    for (Index r = 0; r <= k; ++r) col[r] *= inv;
  }
}

// ------------------------------------------------------------------------------------ input

// Scales the rows of `a` (m x n) to unit length, row_scale_ = 1 / |row| (0 for an all-zero row) from
// index `first` on, and copies into rows_ the rows listed in `copy` (count of them; nullptr: all;
// the scale of a row left out is not meaningful and never read).
// Returns the first row holding NaN or Inf, or -1: every row is checked, copied or not.
// The squared norms accumulate down the contiguous columns of `a` and the square roots and
// divisions go through Eigen's vectorised array functions in one batch; one row at a time,
// their latency dominated the whole load. The largest |entry| of each row, accumulated in the
// same pass, tells an all-zero row (a constraint that bounds nothing this cycle: most
// self-collision pairs) without reading it again across the columns.
Index QpSolver::load_rows(const Eigen::MatrixXd& a, Index first, const Index* copy, Index count) {
  const Index n = n_;
  const Index m = a.rows();
  if (m == 0) return -1;
  double* scale = row_scale_.data() + first;
  double* peak = row_peak_.data();  // per row, max |a_ij| (read only where the squares sum to zero: no NaN)
  // Four rows at a time, their sums in registers down the columns; the last m % 4 one by one.
  const double* data = a.data();
  Index i0 = 0;
  for (; i0 + 4 <= m; i0 += 4) {
    Eigen::Array4d squares = Eigen::Array4d::Zero(), largest = Eigen::Array4d::Zero();
    for (Index j = 0; j < n; ++j) {
      const Eigen::Array4d v = Eigen::Map<const Eigen::Array4d>(data + j * m + i0);
      squares += v * v;
      largest = largest.max(v.abs());
    }
    Eigen::Map<Eigen::Array4d>(scale + i0) = squares;
    Eigen::Map<Eigen::Array4d>(peak + i0) = largest;
  }
  for (; i0 < m; ++i0) {
    double squares = 0.0, largest = 0.0;
    for (Index j = 0; j < n; ++j) {
      const double v = data[j * m + i0];
      squares += v * v;
      largest = std::max(largest, std::abs(v));
    }
    scale[i0] = squares;
    peak[i0] = largest;
  }
  auto scales = row_scale_.segment(first, m).array();
  scales = scales.sqrt().inverse();
  const double min_scale = 1.0 / std::sqrt(kMax);
  const double max_scale = 1.0 / std::sqrt(std::numeric_limits<double>::min());
  bool in_range = true;
  if (copy == nullptr) {
    for (Index i = 0; i < m; ++i) in_range &= scale[i] >= min_scale && scale[i] <= max_scale;
  } else {
    // The rows left out bound nothing and their scale is never read: only a NaN or Inf in them
    // matters, which makes the scale NaN or 0 (an all-zero row's is +inf, and passes).
    for (Index t = 0; t < count; ++t) {
      const double listed = scale[copy[t] - first];
      in_range &= listed >= min_scale && listed <= max_scale;
    }
    for (Index i = 0; i < m; ++i) in_range &= scale[i] > 0.0;
  }
  if (!in_range) {
    // Non-finite, zero (a constraint's row that bounds nothing this cycle: common), or so large or
    // small that the squares leave the double range (rare).
    for (Index i = 0; i < m; ++i) {
      if (scale[i] >= min_scale && scale[i] <= max_scale) continue;
      if (peak[i] == 0.0 && std::isinf(scale[i])) {  // every entry zero (a NaN would make the scale NaN)
        scale[i] = 0.0;
        has_null_rows_ = true;
        continue;
      }
      if (!a.row(i).allFinite()) return i;
      const double norm = a.row(i).stableNorm();
      scale[i] = norm > 0.0 && norm <= kMax ? 1.0 / norm : 0.0;
      has_null_rows_ |= scale[i] == 0.0;
    }
  }
  if (copy == nullptr) {
    for (Index j = 0; j < n; ++j) {
      const double* col = a.col(j).data();
      double* dst = rows_.data() + j + first * n;
      for (Index i = 0; i < m; ++i) dst[i * n] = col[i] * scale[i];
    }
    return -1;
  }
  for (Index t = 0; t < count; ++t) {
    const Index i = copy[t] - first;
    const double* src = a.data() + i;
    double* dst = rows_.data() + (first + i) * n;
    for (Index j = 0; j < n; ++j) dst[j] = src[j * m] * scale[i];
  }
  return -1;
}

namespace {

// Checks l <= u (either may be empty, i.e. absent) and that neither is NaN, l = +inf or u = -inf.
// One branch-free pass; the offending index is searched only on failure.
Index check_sides(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, Index m, bool& inverted) {
  const bool has_lo = lo.size() > 0;
  const bool has_hi = hi.size() > 0;
  bool bad = false;
  if (has_lo && has_hi) {
    // hi - lo >= 0 fails exactly for NaN, lo > hi, lo = hi = +inf and lo = hi = -inf (inf - inf is
    // NaN), and the difference of two doubles is never of the wrong sign: one vectorised test.
    const double* l = lo.data();
    const double* u = hi.data();
    Index failures = 0;
    for (Index i = 0; i < m; ++i) failures += !(u[i] - l[i] >= 0.0);
    bad = failures > 0;
  } else if (has_lo) {
    for (Index i = 0; i < m; ++i) bad |= !(lo(i) < kInf);
  } else if (has_hi) {
    for (Index i = 0; i < m; ++i) bad |= !(hi(i) > -kInf);
  }
  if (!bad) return -1;
  for (Index i = 0; i < m; ++i) {
    const double l = has_lo ? lo(i) : -kInf;
    const double u = has_hi ? hi(i) : kInf;
    inverted = false;
    if (std::isnan(l) || std::isnan(u) || l == kInf || u == -kInf) return i;
    inverted = true;
    if (l > u) return i;
  }
  return -1;
}

// Writes to out the indices first + i of the m rows with a side inside (-big, big) (NaN: not
// listed, check_sides refuses it); returns their count.
Index list_live_rows(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, Index m, Index first, double big,
                     Index* out) {
  const bool has_lo = lo.size() > 0;
  const bool has_hi = hi.size() > 0;
  Index live = 0;
  for (Index i = 0; i < m; ++i) {
    out[live] = first + i;
    live += (has_lo && lo(i) > -big) | (has_hi && hi(i) < big);
  }
  return live;
}

// lower/upper in the scaled units (scale nullptr: unscaled, the bounds), -inf/+inf for absent sides.
void convert_sides(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, const double* scale, Index m, double big,
                   double* lower, double* upper) {
  const auto scaled = [scale](double v, Index i) { return scale == nullptr ? v : v * scale[i]; };
  if (lo.size() > 0) {
    for (Index i = 0; i < m; ++i) lower[i] = lo(i) <= -big ? -kInf : scaled(lo(i), i);
  } else {
    for (Index i = 0; i < m; ++i) lower[i] = -kInf;
  }
  if (hi.size() > 0) {
    for (Index i = 0; i < m; ++i) upper[i] = hi(i) >= big ? kInf : scaled(hi(i), i);
  } else {
    for (Index i = 0; i < m; ++i) upper[i] = kInf;
  }
}

}  // namespace

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
  has_null_rows_ = false;

  if (!all_finite(p.b_eq.data(), m_eq_)) {
    invalid_index_ = first_non_finite_row(p.b_eq);
    return QpInvalidReason::kNonFiniteEqualityTarget;
  }
  if ((invalid_index_ = load_rows(p.A_eq, 0, nullptr, 0)) >= 0) return QpInvalidReason::kNonFiniteEqualityRows;
  // The inequality rows with a finite side; the rest bound nothing: neither copied nor scanned.
  live_row_count_ = list_live_rows(p.l, p.u, m_in_, m_eq_, big, live_rows_.data());
  if ((invalid_index_ = load_rows(p.A, m_eq_, live_rows_.data(), live_row_count_)) >= 0) {
    return QpInvalidReason::kNonFiniteInequalityRows;
  }

  bool inverted = false;
  if ((invalid_index_ = check_sides(p.l, p.u, m_in_, inverted)) >= 0) {
    return inverted ? QpInvalidReason::kRowBoundsInverted : QpInvalidReason::kInvalidRowBound;
  }
  if ((invalid_index_ = check_sides(p.lb, p.ub, n, inverted)) >= 0) {
    return inverted ? QpInvalidReason::kVariableBoundsInverted : QpInvalidReason::kInvalidVariableBound;
  }

  for (Index k = 0; k < m_eq_; ++k) lower_(k) = upper_(k) = p.b_eq(k) * row_scale_(k);
  convert_sides(p.l, p.u, row_scale_.data() + m_eq_, m_in_, big, lower_.data() + m_eq_, upper_.data() + m_eq_);
  convert_sides(p.lb, p.ub, nullptr, n, big, lower_.data() + m_rows_, upper_.data() + m_rows_);

  if (has_null_rows_) {
    // An all-zero equality row reads 0 = b: skipped as dependent, its consistency decided here.
    // An all-zero inequality row is l <= 0 <= u or nothing, and never active.
    for (Index k = 0; k < m_eq_; ++k) {
      null_row_infeasible_ |= row_scale_(k) == 0.0 && std::abs(p.b_eq(k)) > tol;
    }
    for (Index i = 0; i < m_in_; ++i) {
      const Index k = m_eq_ + i;
      if (row_scale_(k) != 0.0) continue;
      const double lo = p.l.size() > 0 ? p.l(i) : -kInf;
      const double hi = p.u.size() > 0 ? p.u(i) : kInf;
      null_row_infeasible_ |= (lo > -big && lo > tol) || (hi < big && hi < -tol);
      lower_(k) = -kInf;
      upper_(k) = kInf;
    }
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
  q_ = 0;
  std::fill(sign_.begin(), sign_.end(), std::int8_t{0});
  if (m_eq_ == 0 && !(warm && has_warm_side())) {
    solve_unconstrained();
    j_formed_ = false;
    return;
  }
  form_j();
  for (Index k = 0; k < m_eq_; ++k) add_warm_constraint(k, +1);

  if (warm) {
    // The guess enters as equalities (no step needed: x is recomputed below); absent sides and
    // normals dependent on those already in are skipped.
    for (Index i = 0; i < m_in_; ++i) {
      const Index k = m_eq_ + i;
      const int sign = warm_sign(row_sides_[static_cast<std::size_t>(i)], lower_(k), upper_(k));
      if (sign != 0) add_warm_constraint(k, sign);
    }
    for (Index j = 0; j < n_; ++j) {
      const Index k = m_rows_ + j;
      const int sign = warm_sign(bound_sides_[static_cast<std::size_t>(j)], lower_(k), upper_(k));
      if (sign != 0) add_warm_constraint(k, sign);
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

bool QpSolver::has_warm_side() const {
  for (Index i = 0; i < m_in_; ++i) {
    const Index k = m_eq_ + i;
    if (warm_sign(row_sides_[static_cast<std::size_t>(i)], lower_(k), upper_(k)) != 0) return true;
  }
  for (Index j = 0; j < n_; ++j) {
    const Index k = m_rows_ + j;
    if (warm_sign(bound_sides_[static_cast<std::size_t>(j)], lower_(k), upper_(k)) != 0) return true;
  }
  return false;
}

// x = -H^-1 g = -L^-T (L^-1 g): the minimum with no constraint active, without J.
void QpSolver::solve_unconstrained() {
  const Index n = n_;
  const double* l = chol_.data();
  double* x = x_.data();
  for (Index i = 0; i < n; ++i) x[i] = -g_[i];
  for (Index k = 0; k < n; ++k) {  // L y = -g, column by column
    const double* lk = l + k * n;
    x[k] /= lk[k];
    for (Index i = k + 1; i < n; ++i) x[i] -= lk[i] * x[k];
  }
  for (Index k = n - 1; k >= 0; --k) {  // L' x = y; row k of L' is column k of L
    const double* lk = l + k * n;
    x[k] = (x[k] - dot(lk + k + 1, x + k + 1, n - k - 1)) / lk[k];
  }
}

// The working J: L^-T (formed once per factorisation), before any constraint enters.
void QpSolver::form_j() {
  if (!has_inverse_) {
    invert_factor();
    has_inverse_ = true;
  }
  j_ = inv_chol_;
  j_formed_ = true;
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
    // Rows outside the live list hold stale values; they are not read.
    columns_dot(rows_.data() + m_eq_ * n_, n_, n_, m_in_, x_.data(), row_values_.data());
    for (Index i = 0; i < live_row_count_; ++i) {
      const Index k = live_rows_[static_cast<std::size_t>(i)];
      if (sign_[static_cast<std::size_t>(k)] == 0) consider(k, row_values_(k - m_eq_));
    }
  } else {
    for (Index i = 0; i < live_row_count_; ++i) {
      const Index k = live_rows_[static_cast<std::size_t>(i)];
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
    if (!j_formed_) form_j();  // the unconstrained start (start_working_set) left it out
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
        columns_axpy(j_.data() + q * n, n, n, n - q, step + q, x_.data());
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
