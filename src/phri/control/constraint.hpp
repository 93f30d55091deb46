#pragma once
// phri::Constraint: one stiff safety constraint of the QP (paper section "Safety Features").
// Constraints carry no gamma: they hold the *real* acceleration (push included) within bounds, so
// a push toward a limit is negated. A constraint tightens the bounds on qdd (bound), or fills its
// own rows l <= A qdd <= u (fill_rows), or both. WholeBodyQp calls them in order every cycle:
// bounds start at -inf/+inf and each constraint tightens them.
//
// Some constraints add a comfort ahead of the paper's bound (a braking distance, a faster return
// beyond a limit). When the QP is infeasible with it, relax() drops that comfort for the rest of
// the cycle and WholeBodyQp solves again, rather than falling back to its brake.
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

#include <Eigen/Core>

#include <string_view>

namespace phri {

/// What a constraint reads in one cycle (after the model terms of (q, qd)).
struct ConstraintContext {
  const Model& model;
  const Data& data;
  const Eigen::VectorXd& q;
  const Eigen::VectorXd& qd;
  const Eigen::VectorXd& tau_ext;           ///< estimated external torque [N.m]
  const Eigen::VectorXd& hold_torque;       ///< h - tau_ext: the torque that holds the arm still [N.m]
  const Eigen::VectorXd& torque_limit;      ///< |tau_d| bound per joint [N.m]
  const Eigen::VectorXd& inertia_diagonal;  ///< diag(M) [kg m^2]
};

class Constraint {
public:
  virtual ~Constraint() = default;
  virtual std::string_view type() const = 0;
  /// Rows this constraint fills in A (fixed at construction); 0: bounds only.
  virtual int num_rows() const { return 0; }
  /// A new cycle: the comforts dropped by relax() come back.
  virtual void begin_cycle() {}
  /// Tightens the bounds on qdd: lower = max(lower, ...), upper = min(upper, ...).
  virtual void bound(const ConstraintContext& /*context*/, Eigen::Ref<Eigen::VectorXd> /*lower*/,
                     Eigen::Ref<Eigen::VectorXd> /*upper*/) {}
  /// Whether its rows bound the arm's motion (a distance, a point's speed), so that they hold for
  /// the push the command does not cancel yet as the bounds do; false for rows on the command's
  /// own torque (TorqueLimitConstraint).
  virtual bool rows_bound_the_motion() const { return true; }
  /// Fills its num_rows() rows: l <= a qdd <= u.
  virtual void fill_rows(const ConstraintContext& /*context*/, Eigen::Ref<Eigen::MatrixXd> /*a*/,
                         Eigen::Ref<Eigen::VectorXd> /*l*/, Eigen::Ref<Eigen::VectorXd> /*u*/) {}
  /// After an infeasible solve: drops a comfort beyond the paper's bound for this cycle. True if
  /// it dropped one (the bounds and rows are then filled again and the QP solved again).
  virtual bool relax() { return false; }
};

}  // namespace phri
