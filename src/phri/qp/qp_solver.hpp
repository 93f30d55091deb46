#pragma once
// phri::QpSolver: dense strictly convex QP solver, the dual active-set method of Goldfarb and
// Idnani (Math. Programming 27, 1983), for the small QP the controller solves every cycle:
//
//   minimize 1/2 x'Hx + g'x   s.t.   A_eq x = b_eq,   l <= A x <= u,   lb <= x <= ub
//
// H symmetric positive definite. A double-sided row or bound is ONE constraint that is active at
// most at one side; a bound is a unit row and is never stored as a dense row. resize() allocates
// all workspace; set_hessian, set_hessian_factor, set_active_set and solve never allocate.
//
//   phri::QpProblem qp;
//   qp.resize(7, 0, 17);                    // setup: allocates, every side absent
//   phri::QpSolver solver(7, 0, 17);        // setup: allocates the workspace
//   // every cycle: fill qp.H, qp.g, qp.A, qp.l, qp.u, qp.lb, qp.ub, then
//   const phri::QpStatus status = solver.solve(qp, {.warm_start = true});
//   if (status != phri::QpStatus::kOptimal) {
//     report(to_string(status), to_string(solver.invalid_reason()), solver.invalid_index(),
//            solver.iterations());          // solver.x() is finite whatever the status
//   }
//   apply(solver.x());
//   // H unchanged since the last solve: skip the Cholesky factorisation
//   solver.solve(qp, {.warm_start = true, .reuse_hessian_factor = true});
//
// Multipliers: H x + g + A_eq' y_eq + A' y_row + y_bound = 0, where y_i <= 0 when row i is active
// at its lower side, y_i >= 0 at its upper side, y_i = 0 when inactive (y_eq: any sign).
//
// Warm start: solve(..., {.warm_start = true}) starts from active_rows()/active_bounds(), i.e.
// the last solve's active set or what set_active_set() wrote. The guess is made consistent first
// (linearly dependent constraints skipped, constraints with negative multipliers dropped), so a
// wrong guess costs iterations, never correctness.
//
// Hessian factor: every solve factorises H and keeps the factor, unless reuse_hessian_factor is
// set, which uses the kept factor (from the last solve, set_hessian or set_hessian_factor) and
// does not read problem.H. A failed factorisation keeps no factor.
//
// Status: kOptimal; kInfeasible and kIterationLimit with the last primal iterate in x();
// kInvalidInput with x() = 0 and invalid_reason()/invalid_index() naming the failed check;
// kNumericalError (finite data whose iterates overflowed) with x() = 0. x() is never NaN.
#include <phri/qp/qp_active_side.hpp>
#include <phri/qp/qp_invalid_reason.hpp>
#include <phri/qp/qp_problem.hpp>
#include <phri/qp/qp_settings.hpp>
#include <phri/qp/qp_solve_options.hpp>
#include <phri/qp/qp_status.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace phri {

class QpSolver {
public:
  using Index = Eigen::Index;

  QpSolver() = default;
  QpSolver(Index n, Index m_eq, Index m_in) { resize(n, m_eq, m_in); }

  // Allocates the workspace for n variables, m_eq equality rows and m_in double-sided rows;
  // forgets the Hessian factor and the active set.
  void resize(Index n, Index m_eq, Index m_in);

  Index num_variables() const { return n_; }
  Index num_equalities() const { return m_eq_; }
  Index num_inequalities() const { return m_in_; }

  QpSettings& settings() { return settings_; }
  const QpSettings& settings() const { return settings_; }

  // Factorises H (lower triangle read) for later solves with reuse_hessian_factor. Returns kNone,
  // or the failed check (kDimensionMismatch, kNonFiniteHessian, kHessianNotPositiveDefinite).
  QpInvalidReason set_hessian(const Eigen::Ref<const Eigen::MatrixXd>& hessian);
  // Takes the caller's Cholesky factor: lower-triangular L with H = L L' (strict upper part not
  // read), e.g. Eigen::LLT<Eigen::MatrixXd>::matrixL(). Returns kNone, or kInvalidHessianFactor.
  QpInvalidReason set_hessian_factor(const Eigen::Ref<const Eigen::MatrixXd>& factor_l);

  // Replaces the active set the next warm start begins from (sizes m_in and n, else false and
  // nothing changes).
  bool set_active_set(std::span<const QpActiveSide> rows, std::span<const QpActiveSide> bounds);

  QpStatus solve(const QpProblem& problem, const QpSolveOptions& options = {});

  // ---- results of the last solve (before the first one: kInvalidInput, x() = 0)
  QpStatus status() const { return status_; }
  QpInvalidReason invalid_reason() const { return invalid_reason_; }
  Index invalid_index() const { return invalid_index_; }  // -1 when not applicable
  // Active-set changes (additions and drops, warm-start repairs included); 0 when a warm start
  // was already the optimal active set.
  int iterations() const { return iterations_; }
  const Eigen::VectorXd& x() const { return x_; }
  double objective() const { return objective_; }
  const Eigen::VectorXd& equality_multipliers() const { return y_eq_; }
  const Eigen::VectorXd& row_multipliers() const { return y_row_; }
  const Eigen::VectorXd& bound_multipliers() const { return y_bound_; }
  // The active set (unchanged by an invalid-input solve, so the next warm start keeps it).
  std::span<const QpActiveSide> active_rows() const { return row_sides_; }
  std::span<const QpActiveSide> active_bounds() const { return bound_sides_; }
  // Constraints in the final working set: independent equalities + active rows + active bounds.
  Index active_count() const { return q_; }

private:
  QpInvalidReason load(const QpProblem& problem, bool reuse_factor);
  Index load_rows(const Eigen::MatrixXd& a, Index first, const Index* copy, Index count);
  QpInvalidReason factorize(const Eigen::Ref<const Eigen::MatrixXd>& hessian, Index& bad_index);
  void invert_factor();
  void start_working_set(bool warm);
  bool has_warm_side() const;
  void solve_unconstrained();
  void form_j();
  void add_warm_constraint(Index k, int sign);
  void solve_working_set();
  void polish_active_constraints();
  bool most_violated(Index& k, int& sign);
  QpStatus iterate(int max_iterations);
  void compute_normal_product(Index k, int sign);
  double slack(Index k, int sign) const;
  double active_target(Index j) const;
  void add_constraint(Index k, int sign, double multiplier);
  void drop_constraint(Index j);
  void publish();
  QpStatus finish_invalid(QpInvalidReason reason, Index index);

  QpSettings settings_;
  Index n_ = 0;
  Index m_eq_ = 0;
  Index m_in_ = 0;
  Index m_rows_ = 0;  // m_eq + m_in; constraint k: equality < m_eq <= row < m_rows <= bound

  // Hessian factor: H = L L' with L = chol_ (lower); inv_chol_ = L^-T is the initial J, formed
  // from L when a solve first needs it (has_inverse_).
  Eigen::MatrixXd chol_;
  Eigen::MatrixXd inv_chol_;
  bool has_factor_ = false;
  bool has_inverse_ = false;

  // Rows of A_eq and A, transposed (one contiguous column per row) and scaled to unit length; an
  // inequality row outside live_rows_ is not copied (its column holds an earlier solve's row).
  Eigen::MatrixXd rows_;
  Eigen::VectorXd row_scale_;  // 1 / |row|, 0 for an all-zero row
  Eigen::VectorXd row_peak_;   // load_rows' scratch: max |entry| per row
  Eigen::VectorXd lower_;      // per constraint, in the scaled units; -inf when absent
  Eigen::VectorXd upper_;      // +inf when absent
  Eigen::VectorXd g_;
  bool has_null_rows_ = false;
  bool null_row_infeasible_ = false;

  // Goldfarb-Idnani state: J = L^-T Q and R with Q' L^-1 N = [R; 0] for the q active normals N.
  Eigen::MatrixXd j_;
  bool j_formed_ = false;  // false: no constraint entered yet this solve, j_ not set
  Eigen::MatrixXd r_;
  Index q_ = 0;
  std::vector<Index> active_;       // constraint index per working-set position
  std::vector<std::int8_t> sign_;   // per constraint: 0 inactive, +1 normal a (lower), -1 -a (upper)
  Eigen::VectorXd u_;               // multipliers per working-set position (>= 0 for inequalities)
  Eigen::VectorXd d_;               // J' n for the constraint being added
  Eigen::VectorXd dir_;             // R^-1 d1: dual step direction
  Eigen::VectorXd work_;
  Eigen::VectorXd row_values_;      // A x (scaled rows), for the large-n scan
  // The inequality rows with a finite side (the others can never be violated nor enter), in order,
  // as constraint indices: only these are copied and scanned (most self-collision pairs bound
  // nothing in a cycle).
  std::vector<Index> live_rows_;
  Index live_row_count_ = 0;

  // Published results.
  QpStatus status_ = QpStatus::kInvalidInput;
  QpInvalidReason invalid_reason_ = QpInvalidReason::kDimensionMismatch;
  Index invalid_index_ = -1;
  int iterations_ = 0;
  double objective_ = 0.0;
  Eigen::VectorXd x_;
  Eigen::VectorXd y_eq_;
  Eigen::VectorXd y_row_;
  Eigen::VectorXd y_bound_;
  std::vector<QpActiveSide> row_sides_;
  std::vector<QpActiveSide> bound_sides_;
};

}  // namespace phri
