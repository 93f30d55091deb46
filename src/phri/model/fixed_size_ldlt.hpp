#pragma once
// phri::FixedSizeLdlt<N>: A = L D L^T (L unit lower triangular) for the cycle's small SPD matrices
// whose size is a compile-time constant (6 x 6 task-space matrices such as J J^T). The root-free
// form leaves one division per column on the factorisation's dependent chain (Cholesky adds a
// square root), and the loops, their lengths known, unroll completely: on 6 x 6, factor and solve
// take ~1/6 of Eigen's LLT<Matrix<double, 6, 6>>, which runs its blocked kernels at run-time sizes
// (phri_bench --benchmark_filter=6FactorSolve).
// compute() reads A's lower triangle and says whether A is positive definite: every pivot d_j > 0,
// in exact arithmetic the squares of the Cholesky pivots (a NaN fails, where Eigen's x <= 0 test
// lets it through). No allocation.
#include <Eigen/Core>

namespace phri {

template <int N>
class FixedSizeLdlt {
public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;

  /// Factors the lower triangle of `a`; true when every pivot is > 0 (A positive definite).
  bool compute(const Matrix& a) {
    // Column j of W = L D: A(j:N, j) - sum_{k<j} L(j, k) W(j:N, k), with L(j, k) = W(j, k) / d_k.
#pragma GCC unroll 8
    for (int j = 0; j < N; ++j) {
#pragma GCC unroll 8
      for (int r = j; r < N; ++r) w_(r, j) = a(r, j);
#pragma GCC unroll 8
      for (int k = 0; k < j; ++k) {
        const double l_jk = w_(j, k) * inverse_pivot_[k];
#pragma GCC unroll 8
        for (int r = j; r < N; ++r) w_(r, j) -= l_jk * w_(r, k);
      }
      if (!(w_(j, j) > 0.0)) return ok_ = false;
      inverse_pivot_[j] = 1.0 / w_(j, j);
    }
    return ok_ = true;
  }

  bool ok() const { return ok_; }
  /// The pivots d_j of the last successful compute().
  Vector pivots() const { return inverse_pivot_.cwiseInverse(); }

  /// x <- A^-1 x (after a successful compute()).
  void solve_in_place(Vector& x) const {
    // L z = x with z = D y stored as y = D^-1 z: L(k, i) z_i = W(k, i) y_i.
#pragma GCC unroll 8
    for (int k = 0; k < N; ++k) {
      double s = x[k];
#pragma GCC unroll 8
      for (int i = 0; i < k; ++i) s -= w_(k, i) * x[i];
      x[k] = s * inverse_pivot_[k];
    }
    // L^T x = y: x_k = y_k - sum_{i>k} L(i, k) x_i, L(i, k) = W(i, k) / d_k.
#pragma GCC unroll 8
    for (int k = N - 1; k >= 0; --k) {
      double s = 0.0;
#pragma GCC unroll 8
      for (int i = k + 1; i < N; ++i) s += w_(i, k) * x[i];
      x[k] -= s * inverse_pivot_[k];
    }
  }
  Vector solve(const Vector& b) const {
    Vector x = b;
    solve_in_place(x);
    return x;
  }

private:
  Matrix w_ = Matrix::Identity();  // L D, lower triangle
  Vector inverse_pivot_ = Vector::Ones();
  bool ok_ = true;
};

}  // namespace phri
