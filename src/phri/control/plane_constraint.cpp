// Plane constraint: a frame's origin p stays on the positive side of a plane (e.g. a tool above a
// table), held by the paper's second-order velocity damper (eq. sec-order-vel-damp) on the distance
//
//   d = n . p - offset,   ḋ = n . J_p qd,   d̈ = n . (J_p qdd + J̇_p qd) >= -k (d - d_s) - lambda ḋ
//
// one row n^T J_p qdd >= min_acceleration(d, ḋ) - n . J̇_p qd while d < d_i, free beyond. Like
// the paper's constraints it bounds the real acceleration (push included): a push toward the
// plane is negated.
#include <phri/control/constraint_registry.hpp>
#include <phri/control/task_registry.hpp>
#include <phri/control/velocity_damper.hpp>

#include <phri/model/algorithms.hpp>

#include <limits>

namespace phri {
namespace {

class PlaneConstraint final : public Constraint {
public:
  PlaneConstraint(const Model& model, int frame_id, const Eigen::Vector3d& normal, double offset,
                  const VelocityDamperSettings& damper)
      : frame_id_(frame_id),
        normal_(normal.normalized()),
        offset_(offset),
        influence_distance_(damper.influence_distance),
        damper_(damper),
        jacobian_(Eigen::MatrixXd::Zero(6, model.nv())) {}

  std::string_view type() const override { return "plane"; }
  int num_rows() const override { return 1; }

  void fill_rows(const ConstraintContext& c, Eigen::Ref<Eigen::MatrixXd> a, Eigen::Ref<Eigen::VectorXd> l,
                 Eigen::Ref<Eigen::VectorXd> u) override {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    frame_jacobian(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
    a.row(0).noalias() = normal_.transpose() * jacobian_.topRows<3>();
    const double d = normal_.dot(c.data.frame_placements[static_cast<std::size_t>(frame_id_)].translation()) - offset_;
    const double d_dot = a.row(0).dot(c.qd);
    const double drift = normal_.dot(frame_jdot_qdot(c.model, c.data, frame_id_, ReferenceFrame::kLocalWorldAligned).head<3>());
    l[0] = d < influence_distance_ ? damper_.min_acceleration(d, d_dot) - drift : -kInf;
    u[0] = kInf;
  }

private:
  int frame_id_;
  Eigen::Vector3d normal_;
  double offset_;
  double influence_distance_;
  VelocityDamper damper_;
  Eigen::MatrixXd jacobian_;
};

std::unique_ptr<Constraint> make_plane_constraint(const ConstraintSpec& spec, const ConstraintBuildContext& context) {
  const TaskBuildContext frames{context.model, context.end_effector_frame, 0.0};
  const int frame = task_frame(spec, frames, true);
  const Eigen::Vector3d normal = spec.three("normal", Eigen::Vector3d::UnitZ(), -1.0, 1.0);
  if (normal.norm() < 0.5) spec.fail("normal", "must be a direction (a unit vector in world axes)");
  if (!spec.has("offset_m")) spec.fail("offset_m", "give the plane's offset along the normal (n . p >= offset_m) [m]");
  VelocityDamperSettings damper;
  damper.influence_distance = spec.number("influence_distance_m", 0.05, 1e-3, 1.0);
  damper.safety_distance = spec.number("safety_distance_m", 0.01, 0.0, 1.0);
  damper.xi = spec.number("approach_speed_m_s", 0.1, 1e-3, 2.0);
  damper.amortization = spec.number("amortization", 1.8, 1.0, 10.0);
  if (damper.safety_distance >= damper.influence_distance) {
    spec.fail("safety_distance_m", "must be below influence_distance_m");
  }
  return std::make_unique<PlaneConstraint>(context.model, frame, normal, spec.number("offset_m", 0.0, -10.0, 10.0), damper);
}

}  // namespace

const ConstraintType& plane_constraint_type() {
  static const ConstraintType type{
      "plane",
      "a frame's origin kept on one side of a plane (n . p >= offset_m + safety_distance_m)",
      {"frame", "normal", "offset_m", "influence_distance_m", "safety_distance_m", "approach_speed_m_s", "amortization"},
      &make_plane_constraint};
  return type;
}

}  // namespace phri
