#include <phri/control/whole_body_qp.hpp>

#include <phri/core/error.hpp>
#include <phri/core/filters.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {
WholeBodyQp::Limits WholeBodyQp::checked_limits(const Model& model, const WholeBodyQpSettings& settings) {
  auto fail = [](const std::string& key, const std::string& reason) { throw ConfigError("WholeBodyQpSettings", key, reason); };
  // No default names an arm's frame: the Controller sets the robot's (ControllerSettings::end_effector_frame).
  if (settings.end_effector_frame.empty()) fail("end_effector_frame", "empty: name the end-effector task's frame");
  Limits limits{settings.torque_limit.size() ? settings.torque_limit : model.effort_limits(),
                settings.velocity_limit.size() ? settings.velocity_limit : model.velocity_limits()};
  if (limits.torque.size() != model.nv()) fail("torque_limit", "needs one value per joint");
  if (limits.velocity.size() != model.nv()) fail("velocity_limit", "needs one value per joint");
  if (!(limits.torque.array() > 0).all() || !limits.torque.allFinite()) fail("torque_limit", "must be finite and > 0");
  if (!(limits.velocity.array() > 0).all() || !limits.velocity.allFinite()) {
    fail("velocity_limit", "must be finite and > 0 (the URDF gives none for some joint: set it)");
  }
  if (!(settings.velocity_limit_fraction > 0 && settings.velocity_limit_fraction <= 1)) fail("velocity_limit_fraction", "must be in (0, 1]");
  if (!(settings.joint_safety_fraction >= 0 && settings.joint_safety_fraction < settings.joint_influence_fraction &&
        settings.joint_influence_fraction < 0.5)) {
    fail("joint_influence_fraction", "need 0 <= joint_safety_fraction < joint_influence_fraction < 0.5");
  }
  if (!(settings.joint_damper_amortization >= 1.0)) fail("joint_damper_amortization", "must be >= 1 (overdamped)");
  const VelocityDamperSettings& c = settings.collision;
  if (!(c.safety_distance >= 0 && c.influence_distance > c.safety_distance && c.xi > 0 && c.amortization >= 1.0)) {
    fail("collision", "need 0 <= safety_distance < influence_distance, xi > 0, amortization >= 1");
  }
  const BrakingReserveSettings& reserve = settings.braking_reserve;
  if (!(reserve.reserve_fraction >= 0 && reserve.reserve_fraction <= 1 && reserve.min_speed_fraction > 0 &&
        reserve.min_speed_fraction <= 1 && reserve.return_gain >= 0 && std::isfinite(reserve.return_gain))) {
    fail("braking_reserve", "reserve_fraction must be in [0, 1], min_speed_fraction in (0, 1] and return_gain finite and >= 0");
  }
  if (!(settings.collision_braking.deceleration >= 0 && std::isfinite(settings.collision_braking.deceleration) &&
        settings.collision_braking.gain > 0 && std::isfinite(settings.collision_braking.gain))) {
    fail("collision_braking", "deceleration must be >= 0 and gain > 0");
  }
  if (!(settings.velocity_limit_gain > 0) || !(settings.brake_damping > 0)) fail("velocity_limit_gain", "gains must be > 0");
  if (settings.compliance_deadband.size() &&
      (settings.compliance_deadband.size() != model.nv() || !(settings.compliance_deadband.array() >= 0).all() ||
       !settings.compliance_deadband.allFinite())) {
    fail("compliance_deadband", "needs one finite value >= 0 per joint");
  }
  limits.velocity *= settings.velocity_limit_fraction;
  return limits;
}

namespace {
// The velocity limit's rate per joint: its joint-limit damper's lambda, or the set gain.
Eigen::VectorXd velocity_limit_gains(const JointLimitConstraint& joint_limits, double gain, int nv) {
  Eigen::VectorXd gains = Eigen::VectorXd::Constant(nv, gain);
  for (int i = 0; i < nv; ++i) {
    if (joint_limits.limited(i)) gains[i] = joint_limits.lambda(i);
  }
  return gains;
}
}  // namespace

WholeBodyQp::WholeBodyQp(const Model& model, const CollisionModel* collision, const WholeBodyQpSettings& settings)
    : WholeBodyQp(model, collision, settings, checked_limits(model, settings)) {}

WholeBodyQp::WholeBodyQp(const Model& model, const CollisionModel* collision, const WholeBodyQpSettings& settings,
                         const Limits& limits)
    : settings_(settings),
      nv_(model.nv()),
      deadband_(settings.compliance_deadband.size() ? settings.compliance_deadband : Eigen::VectorXd::Zero(model.nv())),
      qdd_external_(Eigen::VectorXd::Zero(nv_)),
      qdd_desired_(Eigen::VectorXd::Zero(nv_)),
      tau_desired_(Eigen::VectorXd::Zero(nv_)),
      last_good_tau_(Eigen::VectorXd::Zero(nv_)),
      hold_torque_(Eigen::VectorXd::Zero(nv_)),
      inertia_diagonal_(Eigen::VectorXd::Zero(nv_)),
      hessian_diagonal_(Eigen::VectorXd::Zero(nv_)) {
  constexpr std::size_t kReserved = 16;  // more than any configuration declares: no reallocation later
  tasks_.reserve(kReserved);
  constraints_.reserve(kReserved);
  auto ee = std::make_unique<EndEffectorTask>(model, model.frame_id(settings.end_effector_frame),
                                              settings.smoothing_time_constant, TargetLimits{},
                                              settings.singular_value_threshold);
  end_effector_ = ee.get();
  tasks_.push_back(std::move(ee));
  auto posture = std::make_unique<PostureTask>(model, settings.smoothing_time_constant);
  posture_ = posture.get();
  tasks_.push_back(std::move(posture));

  auto joint_limits = std::make_unique<JointLimitConstraint>(
      model, JointLimitSettings{settings.joint_influence_fraction, settings.joint_safety_fraction,
                                settings.joint_damper_amortization},
      limits.velocity);
  auto velocity_limit = std::make_unique<VelocityLimitConstraint>(
      limits.velocity, velocity_limit_gains(*joint_limits, settings.velocity_limit_gain, model.nv()),
      settings.braking_reserve);
  velocity_limit_ = velocity_limit.get();
  joint_limits_ = joint_limits.get();
  // The velocity limit sets the bounds the joint-limit dampers then tighten (paper: qdd_d <=
  // min(ë_p, ë_v) for an upper limit, >= max(...) for a lower one).
  constraints_.push_back(std::move(velocity_limit));
  constraints_.push_back(std::move(joint_limits));
  auto torque = std::make_unique<TorqueLimitConstraint>(limits.torque);
  torque_limit_ = torque.get();
  constraints_.push_back(std::move(torque));
  if (collision) {
    auto pairs = std::make_unique<SelfCollisionConstraint>(model, *collision, settings.collision, settings.collision_braking);
    self_collision_ = pairs.get();
    constraints_.push_back(std::move(pairs));
  }
  if (settings.power_force_limit) {
    if (!collision) throw ConfigError("WholeBodyQpSettings", "power_force_limit", "needs the collision capsules (robot.collision)");
    auto limit = std::make_unique<PowerForceLimitConstraint>(model, *collision, settings.rotor_inertia, *settings.power_force_limit);
    power_force_limit_ = limit.get();
    constraints_.push_back(std::move(limit));
  }
  resize_problem();
}

void WholeBodyQp::resize_problem() {
  int rows = 0;
  for (const auto& constraint : constraints_) rows += constraint->num_rows();
  problem_.resize(nv_, 0, rows);
  solver_.resize(nv_, 0, rows);
  row_shift_.resize(rows);
  braking_lb_.resize(nv_);
  braking_ub_.resize(nv_);
  warm_ = false;
}

Task& WholeBodyQp::add_task(std::unique_ptr<Task> task) {
  if (!task) throw ConfigError("WholeBodyQp", "tasks", "a null task");
  if (find_task(task->name())) throw ConfigError("WholeBodyQp", "tasks", "two tasks named '" + task->name() + "'");
  tasks_.push_back(std::move(task));
  return *tasks_.back();
}

Constraint& WholeBodyQp::add_constraint(std::unique_ptr<Constraint> constraint) {
  if (!constraint) throw ConfigError("WholeBodyQp", "constraints", "a null constraint");
  constraints_.push_back(std::move(constraint));
  resize_problem();
  return *constraints_.back();
}

Task* WholeBodyQp::task_named(std::string_view name) const {
  for (const auto& task : tasks_) {
    if (task->name() == name) return task.get();
  }
  return nullptr;
}
Task* WholeBodyQp::find_task(std::string_view name) { return task_named(name); }
const Task* WholeBodyQp::find_task(std::string_view name) const { return task_named(name); }

// Objective: 1/2 qdd' H qdd + g' qdd, the sum of the tasks' weighted least squares (factor 2 dropped).
void WholeBodyQp::assemble_objective() {
  problem_.H.setZero();
  problem_.g.setZero();
  hessian_diagonal_.setConstant(settings_.regularization);
  ObjectiveTerms objective{problem_.H, hessian_diagonal_, problem_.g};
  for (const auto& task : tasks_) task->add_objective(objective);
  problem_.H.diagonal() += hessian_diagonal_;
}

// Bounds from -inf/+inf tightened by each constraint in order, then each constraint's rows.
void WholeBodyQp::fill_constraints(const ConstraintContext& context) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  problem_.lb.setConstant(-kInf);
  problem_.ub.setConstant(kInf);
  Eigen::Index row = 0;
  for (const auto& constraint : constraints_) {
    constraint->bound(context, problem_.lb, problem_.ub);
    const int n = constraint->num_rows();
    if (n == 0) continue;
    constraint->fill_rows(context, problem_.A.middleRows(row, n), problem_.l.segment(row, n), problem_.u.segment(row, n));
    if (qdd_uncancelled_ && constraint->rows_bound_the_motion()) shift_rows_by_uncancelled_push(row, n);
    row += n;
  }
  if (qdd_uncancelled_) bound_uncancelled_push();
  for (int i = 0; i < nv_; ++i) {
    // Both limits bind (e.g. beyond one): split the difference.
    if (problem_.lb[i] > problem_.ub[i]) problem_.lb[i] = problem_.ub[i] = 0.5 * (problem_.lb[i] + problem_.ub[i]);
  }
}

// The bounds on qdd hold the real acceleration (constraint.hpp): the command's qdd_d plus a_u, the
// push the command does not cancel yet. Each bound only moves inward: ub - max(a_u, 0), lb - min(a_u, 0),
// so an overestimate asks no acceleration beyond the paper's bounds. Where that empties the interval
// and the far bound is the velocity limit's own, it moves too: the arm's acceleration qdd_d + a_u
// then spans the paper's [lb, ub] (splitting the difference left it at (lb + ub + a_u) / 2 > ub; a
// single point qdd_d = ub - a_u left no room for a collision row). A far bound that guards a position
// (a joint-limit damper, a collision braking bound) does not move: an overestimated a_u would drive
// the joint into it. An interval empty before the shift is split below, as before.
void WholeBodyQp::bound_uncancelled_push() {
  for (int i = 0; i < nv_; ++i) {
    const double a = uncancelled_share_ * (*qdd_uncancelled_)[i];
    const bool open = problem_.lb[i] <= problem_.ub[i];
    if (a > 0.0) {
      problem_.ub[i] -= a;
      if (open && problem_.lb[i] > problem_.ub[i] && velocity_limit_ &&
          problem_.lb[i] == velocity_limit_->cycle_lower()[i]) {
        problem_.lb[i] -= a;
      }
    }
    if (a < 0.0) {
      problem_.lb[i] -= a;
      if (open && problem_.ub[i] < problem_.lb[i] && velocity_limit_ &&
          problem_.ub[i] == velocity_limit_->cycle_upper()[i]) {
        problem_.ub[i] -= a;
      }
    }
  }
}

// A row on the motion holds the real acceleration too: l <= a (qdd_d + a_u) <= u, so both sides
// move by a a_u (at the bounds' share), outward as well as inward: a command that brakes a joint
// against the push is no motion toward a collision pair while the push cancels it, and a row that
// read it so would leave the bounds' shift infeasible, to be halved and dropped. a_u is measured
// motion where it speeds a joint up (uncancelled_push.hpp). The torque rows bound the command: kept.
void WholeBodyQp::shift_rows_by_uncancelled_push(Eigen::Index row, int n) {
  auto shift = row_shift_.head(n);
  shift.noalias() = problem_.A.middleRows(row, n).lazyProduct(*qdd_uncancelled_);
  shift *= uncancelled_share_;
  problem_.l.segment(row, n) -= shift;
  problem_.u.segment(row, n) -= shift;
}

bool WholeBodyQp::relax_a_constraint() {
  for (const auto& constraint : constraints_) {
    if (constraint->relax()) return true;
  }
  // Last: the uncancelled push's share of the bounds, halved up to three times (a push beyond what
  // the torque limits can counter is countered as far as they allow, not left whole to the arm),
  // then dropped (the paper's bounds stay).
  if (qdd_uncancelled_ && uncancelled_share_ > 0.2) {
    uncancelled_share_ *= 0.5;
    return true;
  }
  if (qdd_uncancelled_) {
    qdd_uncancelled_ = nullptr;
    return true;
  }
  return false;
}

WholeBodyQpStatus WholeBodyQp::update(const Model& model, const Data& data, const Eigen::VectorXd& q,
                                     const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_ext, double dt,
                                     const Vector6d* ee_wrench_world, const Eigen::VectorXd* uncancelled_acceleration,
                                     const Eigen::VectorXd* release_acceleration) {
  braking_share_ = 1.0;
  if (!q.allFinite() || !qd.allFinite() || !tau_ext.allFinite() || !data.mass_matrix.allFinite() ||
      (uncancelled_acceleration && uncancelled_acceleration->size() != nv_)) {
    tau_desired_ = last_good_tau_;
    status_ = WholeBodyQpStatus::kInvalidInput;
    return status_;
  }
  // qdd_ext = M^-1 tau_ext: what the push alone would do to the arm (through the dead band).
  soft_deadband(tau_ext, deadband_, qdd_external_);
  if (!qdd_external_.isZero(0.0)) data.mass_matrix_llt.solve_in_place(qdd_external_);  // else exactly 0
  // Not finite: ignored (tau_ext, checked above, still bounds the arm).
  qdd_uncancelled_ = uncancelled_acceleration && uncancelled_acceleration->allFinite() ? uncancelled_acceleration : nullptr;
  uncancelled_share_ = 1.0;

  const TaskContext task_context{model, data, q, qd, tau_ext, qdd_external_, ee_wrench_world, dt};
  for (const auto& task : tasks_) task->update(task_context);
  assemble_objective();

  hold_torque_ = data.nonlinear_effects - tau_ext;
  inertia_diagonal_ = data.mass_matrix.diagonal();
  const ConstraintContext constraint_context{model, data, q, qd, tau_ext, hold_torque_, torque_limit(), inertia_diagonal_};
  for (const auto& constraint : constraints_) constraint->begin_cycle();
  // The motion shows a release one period late and the next command answers it (velocity_limit_constraint.hpp).
  if (velocity_limit_) velocity_limit_->set_release(release_acceleration, 2.0 * dt);
  fill_constraints(constraint_context);

  last_solve_options_ = {.warm_start = warm_, .reuse_hessian_factor = false};
  QpStatus qp = solver_.solve(problem_, last_solve_options_);
  ++solve_count_;
  // A comfort beyond the paper's bounds (a faster return, a braking row) that makes the QP
  // infeasible is dropped for this cycle: the paper's bounds rather than the fallback.
  while (qp == QpStatus::kInfeasible && relax_a_constraint()) {
    fill_constraints(constraint_context);
    last_solve_options_ = {.warm_start = false, .reuse_hessian_factor = false};
    qp = solver_.solve(problem_, last_solve_options_);
    ++solve_count_;
  }
  const bool scaled = qp == QpStatus::kInfeasible && settings_.scale_braking && scale_braking();
  if (scaled) qp = solver_.status();
  if (qp == QpStatus::kOptimal && solver_.x().allFinite()) {
    warm_ = true;
    qdd_desired_ = solver_.x();
    // tau_d = M qdd_d + h - tau_ext (the convention stated in the header).
    tau_desired_.noalias() = data.mass_matrix.lazyProduct(qdd_desired_);  // lazy: no general gemv call at n ~ 7
    tau_desired_ += data.nonlinear_effects - tau_ext;
    last_good_tau_ = tau_desired_;
    status_ = scaled ? WholeBodyQpStatus::kBrakingScaled : WholeBodyQpStatus::kOk;
    return status_;
  }
  warm_ = false;
  status_ = qp == QpStatus::kInfeasible       ? WholeBodyQpStatus::kQpInfeasible
            : qp == QpStatus::kIterationLimit ? WholeBodyQpStatus::kQpIterationLimit
                                              : WholeBodyQpStatus::kQpFailed;
  fallback_brake(data, qd, tau_ext);
  return status_;
}

// The bounds that ask the arm to accelerate (ub < 0 or lb > 0: the dampers braking a joint toward
// a limit, the push's shift) cut to `share` of what they ask; the others as filled.
void WholeBodyQp::set_braking_share(double share) {
  for (int i = 0; i < nv_; ++i) {
    problem_.ub[i] = braking_ub_[i] < 0.0 ? share * braking_ub_[i] : braking_ub_[i];
    problem_.lb[i] = braking_lb_[i] > 0.0 ? share * braking_lb_[i] : braking_lb_[i];
  }
}

// Infeasible after the relaxations: when the torque limits leave less braking than the dampers ask
// (a push holding most of a joint's torque while it runs toward a limit), the largest common share
// of those demands the rows still allow, by bisection to 2^-10. Share 0 (no braking asked) first:
// infeasible, the push is beyond the actuators and the fallback brakes. The rows (torque limits,
// collision distances) are kept as they are. The solver ends on the problem at the share found.
bool WholeBodyQp::scale_braking() {
  constexpr int kBisections = 10;
  braking_lb_ = problem_.lb;
  braking_ub_ = problem_.ub;
  const auto solve_at = [&](double share) {
    set_braking_share(share);
    last_solve_options_ = {.warm_start = false, .reuse_hessian_factor = false};
    ++solve_count_;
    return solver_.solve(problem_, last_solve_options_) == QpStatus::kOptimal;
  };
  if (!solve_at(0.0)) {
    problem_.lb = braking_lb_;
    problem_.ub = braking_ub_;
    return false;
  }
  double feasible = 0.0, infeasible = 1.0;
  bool last_feasible = true;
  for (int k = 0; k < kBisections; ++k) {
    const double share = 0.5 * (feasible + infeasible);
    last_feasible = solve_at(share);
    (last_feasible ? feasible : infeasible) = share;
  }
  if (!last_feasible) solve_at(feasible);
  braking_share_ = feasible;
  return true;
}

// Safe fallback: a joint damping brake qdd = -D qd, clipped to the joint bounds where they allow it,
// negating the push like the constraints do, and torques clipped to their limits. The brake is
// scaled down as a whole (its direction kept) to what the torque limits allow: clipping one joint
// lets the coupled brake speed it up (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 2718 full_body/custom/17). A joint beyond its limit
// with no brake at all only keeps the brake from pushing it further.
void WholeBodyQp::fallback_brake(const Data& data, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_ext) {
  for (int i = 0; i < nv_; ++i) {
    double a = -settings_.brake_damping * qd[i];
    if (problem_.lb[i] <= problem_.ub[i]) a = std::clamp(a, problem_.lb[i], problem_.ub[i]);
    qdd_desired_[i] = a;
  }
  // tau(s) = hold + s M a, s in [0, 1]: the largest s that keeps every joint within its limit
  // (or, for a joint beyond it already, no further beyond).
  hold_torque_ = data.nonlinear_effects - tau_ext;
  tau_desired_.noalias() = data.mass_matrix.lazyProduct(qdd_desired_);
  double scale = 1.0;
  for (int i = 0; i < nv_; ++i) {
    const double limit = torque_limit()[i], hold = hold_torque_[i], brake = tau_desired_[i];
    if (brake > 0.0) scale = std::min(scale, hold >= limit ? 0.0 : (limit - hold) / brake);
    if (brake < 0.0) scale = std::min(scale, hold <= -limit ? 0.0 : (-limit - hold) / brake);
  }
  scale = std::isfinite(scale) ? std::clamp(scale, 0.0, 1.0) : 0.0;
  qdd_desired_ *= scale;
  tau_desired_ = hold_torque_ + scale * tau_desired_;
  tau_desired_ = tau_desired_.cwiseMax(-torque_limit()).cwiseMin(torque_limit());
  if (!tau_desired_.allFinite()) tau_desired_ = last_good_tau_;
  last_good_tau_ = tau_desired_;
}

}  // namespace phri
