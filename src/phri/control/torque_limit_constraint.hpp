#pragma once
// Torque limits of the QP (paper, "Safety Features"): tau_min <= M qdd + h - tau_ext <= tau_max,
// i.e. rows A = M with bounds -tau_max - h + tau_ext <= M qdd <= tau_max - h + tau_ext. tau_ext
// (the push) is on the torque's side: the limits hold the torque the motors must produce.
#include <phri/control/constraint.hpp>
#include <phri/model/data.hpp>

#include <Eigen/Core>

namespace phri {

class TorqueLimitConstraint final : public Constraint {
public:
  explicit TorqueLimitConstraint(const Eigen::VectorXd& torque_limit) : torque_limit_(torque_limit) {}

  std::string_view type() const override { return "torque_limit"; }
  int num_rows() const override { return static_cast<int>(torque_limit_.size()); }
  /// Its rows hold the torque the command asks, whatever the push adds to the motion.
  bool rows_bound_the_motion() const override { return false; }
  void fill_rows(const ConstraintContext& context, Eigen::Ref<Eigen::MatrixXd> a, Eigen::Ref<Eigen::VectorXd> l,
                 Eigen::Ref<Eigen::VectorXd> u) override {
    rows(context.data, context.tau_ext, a, l, u);
  }

  /// Fills nv rows (A, l, u: blocks of the QP's constraint rows).
  template <class Rows, class Bound>
  void rows(const Data& data, const Eigen::VectorXd& tau_ext, Rows&& a, Bound&& l, Bound&& u) const {
    a = data.mass_matrix;
    l = -torque_limit_ - data.nonlinear_effects + tau_ext;
    u = torque_limit_ - data.nonlinear_effects + tau_ext;
  }
  const Eigen::VectorXd& torque_limit() const { return torque_limit_; }

private:
  Eigen::VectorXd torque_limit_;
};

}  // namespace phri
