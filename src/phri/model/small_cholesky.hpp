#pragma once
// phri::SmallCholesky: L L^T = A for the small dense SPD matrices of the cycle (the mass matrix,
// 6 to ~30 joints). Eigen's LLT<MatrixXd> routes these sizes through its blocked triangular
// kernels; plain loops whose length the compiler knows, with the pivots' inverses stored, cost less
// at 7 joints (phri_bench --benchmark_filter=Cholesky: SmallCholesky* against EigenLlt*). The size
// is fixed at construction, so the kernels for 6 and 7 joints are chosen once then; other sizes run
// the same code with the length read at run time. Same factor as Eigen's LLT (lower triangle of A
// read), to rounding; a pivot that is not > 0 is refused, a NaN included (Eigen's x <= 0 test lets
// it through). compute and the in-place solves do not allocate.
#include <phri/core/error.hpp>

#include <Eigen/Core>

#include <cmath>

namespace phri {

class SmallCholesky {
 public:
  using Index = Eigen::Index;

  explicit SmallCholesky(Index n = 0) : l_(Eigen::MatrixXd::Identity(n, n)), inverse_diagonal_(Eigen::VectorXd::Ones(n)) {
    if (n == 6) {
      factor_ = &factor_kernel<6>;
      solve_ = &solve_kernel<6>;
    } else if (n == 7) {
      factor_ = &factor_kernel<7>;
      solve_ = &solve_kernel<7>;
    }
  }

  Index size() const { return l_.rows(); }
  // Whether the last compute succeeded (A symmetric positive definite to its pivots).
  bool ok() const { return ok_; }
  // L, lower triangle; the strict upper part holds no meaning.
  const Eigen::MatrixXd& factor() const { return l_; }

  // Factors the lower triangle of `a` (n x n, n == size(); another size is an ArgumentError). Returns ok().
  bool compute(const Eigen::Ref<const Eigen::MatrixXd>& a) {
    check_size("SmallCholesky::compute", "rows", a.rows(), l_.rows());
    check_size("SmallCholesky::compute", "cols", a.cols(), l_.rows());
    ok_ = factor_(l_.rows(), a.data(), a.outerStride(), l_.data(), inverse_diagonal_.data());
    return ok_;
  }

  // Factors A (into `plain`) and A + diag(shift) (into `shifted`), both of size(), in one pass: the
  // two factorisations' latency chains (a square root and a division per column) interleave. Each
  // factor is the one compute() gives, bit for bit (the same operations in the same order). Returns
  // plain.ok() && shifted.ok().
  static bool compute_with_shifted(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::VectorXd& shift,
                                   SmallCholesky& plain, SmallCholesky& shifted) {
    const Index n = plain.size();
    check_size("SmallCholesky::compute_with_shifted", "rows", a.rows(), n);
    check_size("SmallCholesky::compute_with_shifted", "cols", a.cols(), n);
    check_size("SmallCholesky::compute_with_shifted", "shift", shift.size(), n);
    check_size("SmallCholesky::compute_with_shifted", "shifted factor", shifted.size(), n);
    Factors both{plain.l_.data(), plain.inverse_diagonal_.data(), shifted.l_.data(), shifted.inverse_diagonal_.data()};
    const bool ok = n == 7   ? factor_pair_kernel<7>(n, a.data(), a.outerStride(), shift.data(), both)
                    : n == 6 ? factor_pair_kernel<6>(n, a.data(), a.outerStride(), shift.data(), both)
                             : factor_pair_kernel<0>(n, a.data(), a.outerStride(), shift.data(), both);
    plain.ok_ = both.plain_ok;
    shifted.ok_ = both.shifted_ok;
    return ok;
  }

  // x <- A^-1 x for a vector, or column by column for a matrix (rows == size(), else ArgumentError).
  template <typename Derived>
  void solve_in_place(Eigen::MatrixBase<Derived>& x) const {
    static_assert(Derived::InnerStrideAtCompileTime == 1 && (!Derived::IsRowMajor || Derived::ColsAtCompileTime == 1),
                  "SmallCholesky solves contiguous columns");
    check_size("SmallCholesky::solve_in_place", "rows", x.rows(), l_.rows());
    for (Index c = 0; c < x.cols(); ++c) solve_(l_.rows(), l_.data(), inverse_diagonal_.data(), &x.coeffRef(0, c));
  }
  template <typename Derived>
  void solve_in_place(Eigen::MatrixBase<Derived>&& x) const {
    solve_in_place(x);
  }

  // x <- A^-1 x and y <- A^-1 y, each bit for bit solve_in_place's, with the two solves' dependent
  // chains interleaved (each step waits on the one before; side by side, one hides the other's latency).
  void solve_pair_in_place(Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    check_size("SmallCholesky::solve_pair_in_place", "rows", x.size(), l_.rows());
    check_size("SmallCholesky::solve_pair_in_place", "rows", y.size(), l_.rows());
    const Index n = l_.rows();
    if (n == 7) {
      solve_pair_kernel<7>(n, l_.data(), inverse_diagonal_.data(), x.data(), y.data());
    } else if (n == 6) {
      solve_pair_kernel<6>(n, l_.data(), inverse_diagonal_.data(), x.data(), y.data());
    } else {
      solve_pair_kernel<0>(n, l_.data(), inverse_diagonal_.data(), x.data(), y.data());
    }
  }

 private:
  // N > 0: the size known to the compiler; 0: read from `size`. Right-looking: once column j is
  // final it updates the trailing columns, each a contiguous axpy.
  template <int N>
  static bool factor_kernel(Index size, const double* a, Index lda, double* l, double* inverse_diagonal) {
    const Index n = N > 0 ? N : size;
    for (Index j = 0; j < n; ++j) {
      for (Index i = j; i < n; ++i) l[i + j * n] = a[i + j * lda];
    }
    for (Index j = 0; j < n; ++j) {
      double* col = l + j * n;
      const double pivot = col[j];
      if (!(pivot > 0.0)) return false;
      const double d = std::sqrt(pivot);
      const double inv = 1.0 / d;
      col[j] = d;
      inverse_diagonal[j] = inv;
      for (Index i = j + 1; i < n; ++i) col[i] *= inv;
      for (Index k = j + 1; k < n; ++k) {
        double* trailing = l + k * n;
        const double lkj = col[k];
        for (Index i = k; i < n; ++i) trailing[i] -= lkj * col[i];
      }
    }
    return true;
  }

  struct Factors {
    double *plain_l, *plain_inverse_diagonal, *shifted_l, *shifted_inverse_diagonal;
    bool plain_ok = true, shifted_ok = true;
  };

  // factor_kernel's steps on A and on A + diag(shift) side by side. A factor whose pivot fails stops
  // being updated (its ok flag false); the other goes on.
  template <int N>
  static bool factor_pair_kernel(Index size, const double* a, Index lda, const double* shift, Factors& f) {
    const Index n = N > 0 ? N : size;
    double* l1 = f.plain_l;
    double* l2 = f.shifted_l;
    for (Index j = 0; j < n; ++j) {
      for (Index i = j; i < n; ++i) l1[i + j * n] = l2[i + j * n] = a[i + j * lda];
      l2[j + j * n] += shift[j];
    }
    for (Index j = 0; j < n && (f.plain_ok || f.shifted_ok); ++j) {
      double* c1 = l1 + j * n;
      double* c2 = l2 + j * n;
      f.plain_ok = f.plain_ok && c1[j] > 0.0;
      f.shifted_ok = f.shifted_ok && c2[j] > 0.0;
      const double d1 = std::sqrt(f.plain_ok ? c1[j] : 1.0), d2 = std::sqrt(f.shifted_ok ? c2[j] : 1.0);
      const double inv1 = 1.0 / d1, inv2 = 1.0 / d2;
      c1[j] = d1;
      c2[j] = d2;
      f.plain_inverse_diagonal[j] = inv1;
      f.shifted_inverse_diagonal[j] = inv2;
      for (Index i = j + 1; i < n; ++i) {
        c1[i] *= inv1;
        c2[i] *= inv2;
      }
      for (Index k = j + 1; k < n; ++k) {
        double* t1 = l1 + k * n;
        double* t2 = l2 + k * n;
        const double lkj1 = c1[k], lkj2 = c2[k];
        for (Index i = k; i < n; ++i) {
          t1[i] -= lkj1 * c1[i];
          t2[i] -= lkj2 * c2[i];
        }
      }
    }
    return f.plain_ok && f.shifted_ok;
  }

  // Multiplies by the stored inverse pivots: a division on each step of the two dependent chains
  // would set their latency.
  template <int N>
  static void solve_kernel(Index size, const double* l, const double* inverse_diagonal, double* x) {
    const Index n = N > 0 ? N : size;
    for (Index k = 0; k < n; ++k) {  // L y = x
      double s = x[k];
      for (Index i = 0; i < k; ++i) s -= l[k + i * n] * x[i];
      x[k] = s * inverse_diagonal[k];
    }
    for (Index k = n - 1; k >= 0; --k) {  // L^T x = y; row k of L^T is column k of L
      const double* lk = l + k * n;
      double s = x[k];
      for (Index i = k + 1; i < n; ++i) s -= lk[i] * x[i];
      x[k] = s * inverse_diagonal[k];
    }
  }

  // solve_kernel on two right-hand sides, step by step.
  template <int N>
  static void solve_pair_kernel(Index size, const double* l, const double* inverse_diagonal, double* x, double* y) {
    const Index n = N > 0 ? N : size;
    for (Index k = 0; k < n; ++k) {
      double s = x[k], t = y[k];
      for (Index i = 0; i < k; ++i) {
        s -= l[k + i * n] * x[i];
        t -= l[k + i * n] * y[i];
      }
      x[k] = s * inverse_diagonal[k];
      y[k] = t * inverse_diagonal[k];
    }
    for (Index k = n - 1; k >= 0; --k) {
      const double* lk = l + k * n;
      double s = x[k], t = y[k];
      for (Index i = k + 1; i < n; ++i) {
        s -= lk[i] * x[i];
        t -= lk[i] * y[i];
      }
      x[k] = s * inverse_diagonal[k];
      y[k] = t * inverse_diagonal[k];
    }
  }

  Eigen::MatrixXd l_;
  Eigen::VectorXd inverse_diagonal_;
  bool ok_ = true;
  bool (*factor_)(Index, const double*, Index, double*, double*) = &factor_kernel<0>;
  void (*solve_)(Index, const double*, const double*, double*) = &solve_kernel<0>;
};

}  // namespace phri
