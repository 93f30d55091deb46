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

  Eigen::MatrixXd l_;
  Eigen::VectorXd inverse_diagonal_;
  bool ok_ = true;
  bool (*factor_)(Index, const double*, Index, double*, double*) = &factor_kernel<0>;
  void (*solve_)(Index, const double*, const double*, double*) = &solve_kernel<0>;
};

}  // namespace phri
