// Frame task: a link's position along chosen world axes (e.g. the elbow's height), with its own
// weight and gamma:
//
//   w || S (J_p qdd + J̇_p qd - K (p* - p) - D (0 - v) - gamma J_p M^-1 tau_ext) ||^2
//
// J_p the frame's linear Jacobian (world axes), S the selection of axes (0 or 1 each, or between),
// p* the target (where the frame is when the controller starts, unless given).
#include <phri/control/task_registry.hpp>

#include <phri/model/algorithms.hpp>

namespace phri {
namespace {

class FrameTask final : public Task {
public:
  FrameTask(const Model& model, int frame_id, const TaskSpec& spec)
      : Task(spec.name, task_role(spec, ComplianceRole::kNone)),
        frame_id_(frame_id),
        selection_(spec.three("selection", Eigen::Vector3d::Ones(), 0.0, 1.0)),
        stiffness_(spec.three("stiffness", Eigen::Vector3d::Constant(100.0), 0.0, 1e4)),
        damping_(spec.three("damping", 2.0 * stiffness_.cwiseSqrt(), 0.0, 1e3)),
        gamma_(spec.three("gamma", Eigen::Vector3d::Zero(), 0.0, 1.0)),
        weight_(spec.number("weight", 100.0, 0.0, 1e8)),
        fixed_gamma_(role() == ComplianceRole::kNone || spec.has("gamma")),
        given_target_(spec.has("target_m")),
        target_(spec.three("target_m", Eigen::Vector3d::Zero(), -10.0, 10.0)),
        jacobian_(Eigen::MatrixXd::Zero(6, model.nv())),
        rows_(Eigen::MatrixXd::Zero(3, model.nv())),
        weighted_rows_(Eigen::MatrixXd::Zero(3, model.nv())) {}

  std::string_view type() const override { return "frame"; }
  void start(const Model&, const Data& data) override {
    if (!given_target_) target_ = data.frame_placements[static_cast<std::size_t>(frame_id_)].translation();
  }
  void set_role_gamma(double gamma) override {
    if (!fixed_gamma_) gamma_.setConstant(gamma);
  }
  bool fixed_gamma() const override { return fixed_gamma_; }

  void update(const TaskContext& c) override {
    frame_jacobian(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
    rows_ = jacobian_.topRows<3>();
    const Eigen::Vector3d p = c.data.frame_placements[static_cast<std::size_t>(frame_id_)].translation();
    const Eigen::Vector3d v = frame_velocity(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned).head<3>();
    const Eigen::Vector3d drift = frame_jdot_qdot(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned).head<3>();
    error_ = target_ - p;
    external_.noalias() = rows_.lazyProduct(c.qdd_external);
    reference_ = stiffness_.cwiseProduct(error_) - damping_.cwiseProduct(v) - drift + gamma_.cwiseProduct(external_);
    weighted_rows_ = rows_;
    weighted_rows_.array().colwise() *= selection_.array();
  }

  void add_objective(ObjectiveTerms& objective) const override {
    objective.add_least_squares(weight_, rows_, weighted_rows_, reference_);
  }

private:
  int frame_id_;
  Eigen::Vector3d selection_, stiffness_, damping_, gamma_;
  double weight_;
  bool fixed_gamma_;
  bool given_target_;
  Eigen::Vector3d target_;
  Eigen::MatrixXd jacobian_, rows_, weighted_rows_;
  Eigen::Vector3d error_ = Eigen::Vector3d::Zero(), external_ = Eigen::Vector3d::Zero(),
                  reference_ = Eigen::Vector3d::Zero();
};

std::unique_ptr<Task> make_frame_task(const TaskSpec& spec, const TaskBuildContext& context) {
  return std::make_unique<FrameTask>(context.model, task_frame(spec, context, true), spec);
}

}  // namespace

const TaskType& frame_task_type() {
  static const TaskType type{"frame",
                             "a link's position along chosen world axes",
                             {"frame", "selection", "target_m", "stiffness", "damping", "weight", "gamma", "role"},
                             &make_frame_task};
  return type;
}

}  // namespace phri
