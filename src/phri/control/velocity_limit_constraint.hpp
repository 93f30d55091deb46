#pragma once
// Joint velocity limits of the QP (paper: 0.9 of the robot's limits), as bounds on qdd that drive
// qd back within +-v_max at the rate lambda: qdd <= -lambda (qd - v_max), qdd >= -lambda (qd + v_max).
// lambda per joint: its joint-limit damper's for a limited joint, a set gain for a continuous one.
//
// Braking reserve (ours, not the paper's). A limit the joint can reach is only as good as the
// torque left to stop it there. Moving toward +, a joint brakes with tau >= -tau_max, which leaves
// the reserve tau_max + hold, hold = h - tau_ext being the torque that holds it against gravity,
// its motion and the push (toward -: tau_max - hold); a push that takes nearly all of it leaves
// too little to brake from v_max (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 5150 full_body/custom/17). So below
// reserve_fraction x tau_max of reserve in a direction, that direction's limit falls linearly
// with the reserve, down to min_speed_fraction x v_max at none. A joint already faster than the
// lowered limit is asked no more deceleration than its reserve gives (reserve / (M_ii lambda) of
// speed per cycle's bound), and with a negative reserve no less acceleration than the torque limit
// forces, so the lowered limit never makes the QP infeasible by itself.
//
// Release bound (ours, not the paper's). In a torque loop the command cancels the estimated push;
// if the hand lets go, the arm gets a_r = (M + B)^-1 (-tau_ext) on top of qdd_d until the motion
// shows the release (one period) and the next command answers it (one more): over that horizon
// h = 2 dt the bounds do not see it coming. So on the side a_r points to, qdd_d + a_r is held to
// what keeps the speed within the limit over h: qdd_d <= (v - qd) / h - a_r (a_r > 0; mirrored
// below). It bounds the speed reached, not the way there: near the limit it is the tighter bound,
// away from it (500/s against the damper's 50/s) it never binds, so a joint braking against a push
// keeps the damper's whole range. (Lowering v itself by h |a_r| instead throttled that braking
// through the damper's gain and left a UR5e pinned on its self-collision bounds.) set_release()
// gives a_r and h each cycle; dropped by relax() like the return gain.
#include <phri/control/constraint.hpp>

#include <Eigen/Core>

#include <algorithm>

namespace phri {

struct BrakingReserveSettings {
  /// Reserve (fraction of the torque limit) from which a direction keeps its full limit; 0: off.
  double reserve_fraction = 0.3;
  /// The limit's fraction with no reserve left.
  double min_speed_fraction = 0.5;
  /// [1/s] The bound's gain once a joint is beyond its limit, within its reserve (deceleration());
  /// dropped where it makes the QP infeasible; 0: off.
  double return_gain = 200.0;
};

class VelocityLimitConstraint final : public Constraint {
public:
  VelocityLimitConstraint(const Eigen::VectorXd& velocity_limit, const Eigen::VectorXd& gain,
                          const BrakingReserveSettings& reserve = {0.0, 1.0, 0.0})
      : velocity_limit_(velocity_limit),
        gain_(gain),
        reserve_(reserve),
        lower_(Eigen::VectorXd::Zero(velocity_limit.size())),
        upper_(Eigen::VectorXd::Zero(velocity_limit.size())),
        release_(Eigen::VectorXd::Zero(velocity_limit.size())) {}

  /// The release bound's acceleration a_r for this cycle (header), or null for none; horizon_s: the
  /// time before a command answers a release (2 control periods).
  void set_release(const Eigen::VectorXd* release_acceleration, double horizon_s) {
    if (!release_acceleration || release_acceleration->size() != release_.size() || !release_acceleration->allFinite() ||
        !(horizon_s > 0.0)) {
      release_.setZero();
      return;
    }
    release_ = *release_acceleration;
    release_horizon_ = horizon_s;
  }

  std::string_view type() const override { return "velocity_limit"; }
  void begin_cycle() override { relaxed_ = false; }
  /// Tightens the bounds by the reserve-lowered limits, with the return gain unless relaxed.
  void bound(const ConstraintContext& context, Eigen::Ref<Eigen::VectorXd> lower,
             Eigen::Ref<Eigen::VectorXd> upper) override {
    bound(context.qd, context.hold_torque, context.torque_limit, context.inertia_diagonal, lower_, upper_, !relaxed_,
          !relaxed_);
    lower = lower.cwiseMax(lower_);
    upper = upper.cwiseMin(upper_);
  }
  /// Drops the return gain and the release bound for this cycle (the paper's bounds rather than
  /// the fallback brake).
  bool relax() override {
    if (relaxed_ || (!returning_ && !release_bound_)) return false;
    relaxed_ = true;
    return true;
  }

  /// Sets the acceleration bounds from the velocity limits.
  void bound(const Eigen::VectorXd& qd, Eigen::Ref<Eigen::VectorXd> lower, Eigen::Ref<Eigen::VectorXd> upper) const {
    for (int i = 0; i < qd.size(); ++i) {
      upper[i] = -gain_[i] * (qd[i] - velocity_limit_[i]);
      lower[i] = -gain_[i] * (qd[i] + velocity_limit_[i]);
    }
  }

  /// The same with each direction's limit lowered by its braking reserve (header). hold: h - tau_ext;
  /// inertia: the diagonal of M (what one N.m of reserve decelerates).
  /// with_return: the return gain beyond the limit (deceleration()); returning() then tells whether
  /// it asked more than the paper's gain on some joint. with_release: the release bound (header).
  void bound(const Eigen::VectorXd& qd, const Eigen::VectorXd& hold, const Eigen::VectorXd& torque_limit,
             const Eigen::VectorXd& inertia, Eigen::Ref<Eigen::VectorXd> lower, Eigen::Ref<Eigen::VectorXd> upper,
             bool with_return = true, bool with_release = false) {
    returning_ = false;
    release_bound_ = false;
    for (int i = 0; i < qd.size(); ++i) {
      const double up_reserve = torque_limit[i] + hold[i], down_reserve = torque_limit[i] - hold[i];
      const double up = speed_limit(i, up_reserve, torque_limit[i], qd[i], inertia[i]);
      const double down = speed_limit(i, down_reserve, torque_limit[i], -qd[i], inertia[i]);
      upper[i] = -deceleration(i, qd[i] - up, up_reserve, inertia[i], with_return);
      lower[i] = deceleration(i, -qd[i] - down, down_reserve, inertia[i], with_return);
      if (!with_release || release_[i] == 0.0) continue;
      if (release_[i] > 0.0) {
        const double released = (velocity_limit_[i] - qd[i]) / release_horizon_ - release_[i];
        release_bound_ = release_bound_ || released < upper[i];
        upper[i] = std::min(upper[i], released);
      } else {
        const double released = (-velocity_limit_[i] - qd[i]) / release_horizon_ - release_[i];
        release_bound_ = release_bound_ || released > lower[i];
        lower[i] = std::max(lower[i], released);
      }
    }
  }

  /// The deceleration asked of joint i, `over` faster than its limit in one direction (negative:
  /// below it, an acceleration allowed): gain x over, and beyond the limit up to return_gain x over
  /// within what the direction's reserve decelerates the joint at (reserve / M_ii): the paper's 50/s
  /// alone is too slow where two joints share an axis, and unbounded by the reserve the return gain
  /// makes the QP infeasible (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 60606 full_body/custom/23).
  double deceleration(int i, double over, double reserve, double inertia, bool with_return) {
    const double paper = gain_[i] * over;
    if (!with_return || !(over > 0.0) || !(reserve_.return_gain > gain_[i])) return paper;
    const double returning = std::min(reserve_.return_gain * over, std::max(reserve, 0.0) / inertia);
    if (!(returning > paper)) return paper;
    returning_ = true;
    return returning;
  }
  /// Whether the last bound() asked more than the paper's gain somewhere (WholeBodyQp drops it when
  /// the QP is infeasible with it).
  bool returning() const { return returning_; }

  /// The speed limit of joint i in one direction, given the torque reserve to brake a motion that
  /// way and the joint's speed along it.
  double speed_limit(int i, double reserve, double torque_limit, double speed, double inertia) const {
    const double v = velocity_limit_[i];
    if (!(reserve_.reserve_fraction > 0.0)) return v;
    const double fraction = std::clamp(reserve / (reserve_.reserve_fraction * torque_limit), reserve_.min_speed_fraction, 1.0);
    const double lowered = fraction * v;
    if (fraction >= 1.0 || speed <= lowered) return lowered;
    // Faster than the lowered limit: the bound asks gain x slack of deceleration, what the reserve
    // gives. With less than none it lets through the acceleration the torque cannot stop: asking for
    // less makes the QP infeasible (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 5150 full_body/custom/17).
    const double slack = reserve / (inertia * gain_[i]);
    return slack >= 0.0 ? std::max(lowered, std::min(speed, v) - slack) : std::min(speed, v) - slack;
  }

  const Eigen::VectorXd& velocity_limit() const { return velocity_limit_; }
  /// This cycle's bounds on qdd from the velocity limits alone (the last bound(context, ...)).
  const Eigen::VectorXd& cycle_lower() const { return lower_; }
  const Eigen::VectorXd& cycle_upper() const { return upper_; }

private:
  Eigen::VectorXd velocity_limit_, gain_;
  BrakingReserveSettings reserve_;
  bool returning_ = false;  // the last bound() asked more than the paper's gain somewhere
  bool relaxed_ = false;    // the return gain and the release bound dropped for this cycle
  bool release_bound_ = false;  // the last bound() was tightened by the release bound somewhere
  Eigen::VectorXd lower_, upper_;  // this cycle's bounds before tightening the QP's
  Eigen::VectorXd release_;       // a_r (set_release), zero for none
  double release_horizon_ = 2e-3;  // h [s]
};

}  // namespace phri
