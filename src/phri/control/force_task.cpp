// Cartesian force task (not in the paper; the classic polishing and insertion use): the end
// effector presses with the force f* along an axis n while other tasks hold the other axes:
//
//   w || n^T (J qdd + J̇ qd) - D (v* - n^T v) - gamma n^T J M^-1 tau_ext ||^2
//   v* = clamp(g (f* - f) / (Lambda_n D), +-v_max)
//
// f = -n^T F is the force the end effector applies along n, F the environment's wrench on the
// robot (world axes): the F/T sensor's when a plausible one is in use, else the least-squares
// wrench that explains tau_ext, (J J^T)^-1 J tau_ext. Lambda_n = n^T (J M^-1 J^T)^-1 n is the end
// effector's inertia along n with its other axes held. In contact (v = 0) the task asks the
// acceleration g (f* - f) / Lambda_n, i.e. the extra force g (f* - f): a force loop of gain g
// (dimensionless, default 1) whatever the arm's posture. Inverse dynamics holds the contact force
// the observer has already seen (tau_d = M qdd + h - tau_ext), which makes the loop integral: the
// force converges to f* at the observer's rate. In free space the same law approaches the surface
// at g f* / (Lambda_n D), at most v_max.
#include <phri/control/task_registry.hpp>

#include <phri/model/algorithms.hpp>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace phri {
namespace {

class ForceTask final : public Task {
public:
  ForceTask(const Model& model, int frame_id, const TaskSpec& spec)
      : Task(spec.name, task_role(spec, ComplianceRole::kNone)),
        frame_id_(frame_id),
        frame_axes_(spec.word("axes", "world", {"world", "frame"}) == "frame"),
        force_(spec.number("force_N", 10.0, -200.0, 200.0)),
        gain_(spec.number("force_gain", 1.0, 0.0, 2.0)),
        damping_(spec.number("damping", 100.0, 1.0, 1e3)),
        max_speed_(spec.number("max_speed_m_s", 0.02, 0.0, 0.5)),
        weight_(spec.number("weight", 1e4, 0.0, 1e8)),
        gamma_(spec.number("gamma", 0.0, 0.0, 1.0)),
        fixed_gamma_(role() == ComplianceRole::kNone || spec.has("gamma")),
        jacobian_(Eigen::MatrixXd::Zero(6, model.nv())),
        row_(Eigen::RowVectorXd::Zero(model.nv())),
        mobility_(Eigen::MatrixXd::Zero(model.nv(), 6)) {
    const Eigen::Vector3d axis = spec.three("axis", Eigen::Vector3d(0.0, 0.0, -1.0), -1.0, 1.0);
    if (!(axis.norm() > 1e-6)) spec.fail("axis", "must not be zero");
    axis_ = axis.normalized();
  }

  std::string_view type() const override { return "force"; }
  void set_role_gamma(double gamma) override {
    if (!fixed_gamma_) gamma_ = gamma;
  }
  bool fixed_gamma() const override { return fixed_gamma_; }

  void update(const TaskContext& c) override {
    frame_jacobian(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
    const Eigen::Isometry3d& pose = c.data.frame_placements[static_cast<std::size_t>(frame_id_)];
    const Eigen::Vector3d n = frame_axes_ ? Eigen::Vector3d(pose.linear() * axis_) : axis_;
    row_.noalias() = n.transpose() * jacobian_.topRows<3>();
    const Vector6d wrench = c.ee_wrench_world ? *c.ee_wrench_world : estimated_wrench(c.tau_ext);
    force_measured_ = -n.dot(wrench.head<3>());
    const double speed_target =
        std::clamp(gain_ * (force_ - force_measured_) / (inertia_along(c.data, n) * damping_), -max_speed_, max_speed_);
    const double speed = n.dot(frame_velocity(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned).head<3>());
    const double drift = n.dot(frame_jdot_qdot(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned).head<3>());
    reference_ = damping_ * (speed_target - speed) - drift + gamma_ * row_.dot(c.qdd_external);
  }

  void add_objective(ObjectiveTerms& objective) const override {
    objective.hessian.noalias() += weight_ * row_.transpose() * row_;
    objective.gradient.noalias() -= (weight_ * reference_) * row_.transpose();
  }

private:
  // Lambda_n = n^T (J M^-1 J^T)^-1 n, the task-space inertia along n with the other axes held [kg].
  double inertia_along(const Data& data, const Eigen::Vector3d& n) {
    mobility_ = jacobian_.transpose();
    data.mass_matrix_llt.solve_in_place(mobility_);  // M^-1 J^T
    jjt_.noalias() = jacobian_ * mobility_;
    jjt_.diagonal().array() += 1e-9;
    llt_.compute(jjt_);
    projected_.head<3>() = n;
    projected_.tail<3>().setZero();
    const double inverse = projected_.dot(llt_.solve(projected_));
    return std::max(inverse, 1e-3);
  }

  // The wrench that explains tau_ext at the end effector, least squares: J^T F = tau_ext.
  Vector6d estimated_wrench(const Eigen::VectorXd& tau_ext) {
    jjt_.noalias() = jacobian_ * jacobian_.transpose();
    jjt_.diagonal().array() += 1e-9;  // a singular arm: the least-squares wrench stays finite
    projected_.noalias() = jacobian_ * tau_ext;
    llt_.compute(jjt_);
    return llt_.solve(projected_);
  }

  int frame_id_;
  bool frame_axes_;
  Eigen::Vector3d axis_;
  double force_, gain_, damping_, max_speed_, weight_, gamma_;
  bool fixed_gamma_;
  Eigen::MatrixXd jacobian_;
  Eigen::RowVectorXd row_;
  Eigen::MatrixXd mobility_;  // M^-1 J^T, nv x 6
  double reference_ = 0.0;
  double force_measured_ = 0.0;
  Eigen::Matrix<double, 6, 6> jjt_;
  Vector6d projected_;
  Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt_{6};
};

std::unique_ptr<Task> make_force_task(const TaskSpec& spec, const TaskBuildContext& context) {
  // The F/T wrench is the end effector's: the task acts there.
  return std::make_unique<ForceTask>(context.model, context.end_effector_frame, spec);
}

}  // namespace

const TaskType& force_task_type() {
  static const TaskType type{"force",
                             "a contact force along an axis at the end effector",
                             {"axis", "axes", "force_N", "force_gain", "damping", "max_speed_m_s",
                              "weight", "gamma", "role"},
                             &make_force_task};
  return type;
}

}  // namespace phri
