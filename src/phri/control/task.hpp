#pragma once
// phri::Task: one weighted term of the compliant QP (paper eq. compliantQP):
//
//   w || W^1/2 (A qdd - b) ||^2,   b = a* - A_dot qd + Gamma A M^-1 tau_ext
//
// A task gives its rows A (a Jacobian or a selection, rows x nv), their reference b (the desired
// acceleration with the drift and the compliant part already in), and its weight; WholeBodyQp adds
// every task to H and g in one loop (add_objective). Gamma, in [0, 1] per row, decides how much
// of the estimated external acceleration M^-1 tau_ext the task lets through: 0 negates a push,
// 1 lets the arm move as the push would. The compliance modes set gamma per *role*
// (ComplianceRole); a task declared with its own gamma keeps it whatever the mode.
//
// Tasks are built at start-up (task_registry.hpp builds them from a TaskSpec); update() and
// add_objective() run every cycle and allocate nothing.
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>
#include <phri/model/spatial.hpp>

#include <Eigen/Core>

#include <string>
#include <string_view>

namespace phri {

/// Which gamma a compliance mode gives a task (control/compliance_mode.hpp).
enum class ComplianceRole {
  kMain,       ///< the main task: gamma 1 in full-body compliance and while touched in dual, else 0
  kNullSpace,  ///< the posture: gamma 0 when stiff, else 1
  kNone,       ///< the mode leaves it alone: the task's declared gamma (default 0)
};

/// The QP's objective as the tasks build it: 1/2 qdd^T (H + diag(d)) qdd + g^T qdd. A task whose
/// Hessian is diagonal (a posture, a regularisation) adds to d, which the QP adds to H once: the
/// diagonal's summation order then does not depend on the order tasks are declared in.
struct ObjectiveTerms {
  Eigen::MatrixXd& hessian;
  Eigen::VectorXd& hessian_diagonal;
  Eigen::VectorXd& gradient;

  // w ||W^1/2 (A qdd - b)||^2 with W A given (weighted_rows; A itself when W = I): H += w A^T W A,
  // g -= w (W A)^T b. H's lower triangle from column dots, mirrored, so H stays exactly symmetric;
  // Eigen's product of two dynamic matrices takes its blocked GEMM path at a task's sizes (6 x 7).
  // A pose task's six rows take fixed-size column dots (a dynamic dot's run-time length costs more
  // than its six products).
  void add_least_squares(double w, const Eigen::MatrixXd& rows, const Eigen::MatrixXd& weighted_rows,
                         const Eigen::Ref<const Eigen::VectorXd>& reference) {
    if (rows.rows() == 6 && weighted_rows.rows() == 6 && reference.size() == 6) {
      using Column = Eigen::Map<const Eigen::Matrix<double, 6, 1>>;
      add_least_squares(w, rows.cols(), [&](Eigen::Index c) { return Column(rows.col(c).data()); },
                        [&](Eigen::Index c) { return Column(weighted_rows.col(c).data()); }, Column(reference.data()));
      return;
    }
    add_least_squares(w, rows.cols(), [&](Eigen::Index c) { return rows.col(c); },
                      [&](Eigen::Index c) { return weighted_rows.col(c); }, reference);
  }

private:
  template <class Column, class WeightedColumn, class Reference>
  void add_least_squares(double w, Eigen::Index n, const Column& column, const WeightedColumn& weighted_column,
                         const Reference& reference) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const auto weighted = weighted_column(j);
      gradient[j] -= w * weighted.dot(reference);
      for (Eigen::Index i = j; i < n; ++i) {
        const double term = w * column(i).dot(weighted);
        hessian(i, j) += term;
        if (i != j) hessian(j, i) += term;
      }
    }
  }
};

/// What a task reads in one cycle (all after the model terms of (q, qd)).
struct TaskContext {
  const Model& model;
  const Data& data;
  const Eigen::VectorXd& q;
  const Eigen::VectorXd& qd;
  const Eigen::VectorXd& tau_ext;       ///< estimated external torque (full, no dead band) [N.m]
  const Eigen::VectorXd& qdd_external;  ///< M^-1 tau_ext through the compliance dead band [rad/s^2]
  /// The operator's wrench at the end effector from the F/T sensor (world axes, about the end
  /// effector's origin; force on the robot), or null when no plausible F/T reading is in use.
  const Vector6d* ee_wrench_world;
  double dt;
};

class Task {
public:
  Task(std::string name, ComplianceRole role) : name_(std::move(name)), role_(role) {}
  virtual ~Task() = default;
  Task(const Task&) = delete;
  Task& operator=(const Task&) = delete;

  /// The type's name as written in the run YAML ("pose", "posture", "force", "frame", ...).
  virtual std::string_view type() const = 0;
  const std::string& name() const { return name_; }
  ComplianceRole role() const { return role_; }

  /// The controller starts (first usable sample): a task that holds something holds it where the
  /// arm is now (data after the model terms of the start posture).
  virtual void start(const Model& /*model*/, const Data& /*data*/) {}
  /// Computes this cycle's rows and reference (gamma term included); advances gain filters by dt.
  virtual void update(const TaskContext& context) = 0;
  /// Adds w A^T W A to H (or to d when diagonal) and -w A^T W b to g (the least squares' factor 2
  /// dropped).
  virtual void add_objective(ObjectiveTerms& objective) const = 0;
  /// The gamma a compliance mode asks for this task's role (0 or 1, or a live override in [0, 1]);
  /// ignored when the task keeps a gamma of its own.
  virtual void set_role_gamma(double gamma) = 0;
  /// True when the task was declared with its own gamma (the modes leave it alone).
  virtual bool fixed_gamma() const { return false; }

private:
  std::string name_;
  ComplianceRole role_;
};

}  // namespace phri
