#pragma once
// phri::QpSolveOptions: per-call choices of QpSolver::solve.

namespace phri {

struct QpSolveOptions {
  // Start from QpSolver's current active set (the last solve's, or set_active_set()) instead of
  // the unconstrained minimum. Any guess is safe: it only changes the iteration count.
  bool warm_start = false;
  // H did not change since the last factorisation (a solve, set_hessian or set_hessian_factor):
  // reuse the stored factor and do not read problem.H at all.
  bool reuse_hessian_factor = false;
};

}  // namespace phri
