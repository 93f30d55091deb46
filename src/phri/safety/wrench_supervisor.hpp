#pragma once
// phri::WrenchSupervisor: plausibility of the F/T wrench, as StateSupervisor checks the joints.
// A wrench the controller estimates from must be
//
//   valid (once the sensor has delivered a sample, RobotState::wrench.valid stays true), finite,
//   within the sensor's range per axis, fresh (its sequence and stamp advance within stale_s of the
//   joints' clock: the F/T may sample slower than the 1 kHz cycle), not frozen (bit-identical new
//   samples for frozen_s while the arm moves or the observer sees a load), and consistent with the
//   momentum observer: the joint torque J^T F of the operator's wrench must be found in the
//   observer's tau_ext (both estimate the paper's external torque, the tau^e of eq. compliantQP).
//
// The consistency check is one-sided: it flags the part of J^T F along its own direction that the
// observer does not see. A push elsewhere on the arm (the observer sees it, the F/T does not) or an
// F/T reading less than the hand gives never drives the arm and is not flagged; a phantom wrench
// (stuck after the hand left, a gain or offset fault) is.
//
// A failed check drops the F/T source and latches until reset(): the controller then runs on the
// observer alone and the dual-compliance trigger sees no wrench (Controller::estimate). Latched
// rather than recovered because a sensor that froze or lied once gives no sign of when it is right
// again, and the bias estimated at start-up may no longer hold: reset() (arm at rest, no hand)
// starts over, the wrench estimator re-estimating its bias from the next samples.
// check() and check_consistency() allocate nothing and never throw.
#include <phri/robot/robot_state.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <string_view>

namespace phri {

/// The F/T source's state; every value from kNotFinite on is a latched drop and says why.
enum class WrenchStatus : std::uint8_t {
  kOk = 0,
  kNoSignal,      ///< no valid sample yet (no sensor, or not streaming): not used, not a fault
  kNotFinite,     ///< NaN or infinite component
  kInvalid,       ///< the robot marked the wrench invalid after it had been valid
  kOutOfRange,    ///< a component beyond the sensor's range
  kStale,         ///< no new sample (sequence and stamp advancing) for stale_s
  kFrozen,        ///< bit-identical new samples for frozen_s while the arm moves or is loaded
  kInconsistent,  ///< J^T F not seen by the momentum observer
  kLast = kInconsistent,
};

constexpr std::string_view to_string(WrenchStatus s) {
  switch (s) {
    case WrenchStatus::kOk: return "ok";
    case WrenchStatus::kNoSignal: return "no_signal";
    case WrenchStatus::kNotFinite: return "not_finite";
    case WrenchStatus::kInvalid: return "invalid";
    case WrenchStatus::kOutOfRange: return "out_of_range";
    case WrenchStatus::kStale: return "stale";
    case WrenchStatus::kFrozen: return "frozen";
    case WrenchStatus::kInconsistent: return "inconsistent";
  }
  return "unknown";
}

struct WrenchSupervisorSettings {
  /// [N] per force axis, [N.m] per moment axis: beyond is not a reading. The SensONE's datasheet
  /// range is not in our notes (reference/bota_sensone.md section 6: not found), so these are an
  /// UNVERIFIED assumption, far above any hand (ISO/TS 15066 quasi-static limits: at most 220 N)
  /// and far below garbage such as 1e6 N. Too low only drops the F/T on a real overload (the
  /// observer takes over); too high leaves a saturated reading to the consistency check.
  double force_range_N = 500.0;
  double moment_range_Nm = 20.0;
  /// [s] no new sample for longer: stale. Bota's serial driver calls data older than 0.05 s
  /// invalid (BotaSensOneSettings::stale_after_s, 5 periods at its 100 Hz): the same budget.
  double stale_s = 0.05;
  /// [s] new samples bit-identical this long (the joints' frozen_s, SupervisorSettings) while the
  /// arm moves faster than frozen_speed_rad_s on some joint or the observer sees more than
  /// frozen_load_Nm (norm): strain gauges always carry noise. 0: not checked.
  double frozen_s = 0.05;
  double frozen_speed_rad_s = 0.05;
  double frozen_load_Nm = 2.0;
  /// Consistency with the observer. J^T F is first low-passed at the observer's own bandwidth K_O
  /// (the observer is a first-order lag of the true tau_ext, so both then see a push alike); the
  /// part of it the observer lacks along its direction,
  ///   u = |t| - max(0, t . tau_obs / |t|),
  /// low-passed over consistency_filter_s (0.15 s: a hand letting go of a fast-moving tool leaves
  /// ~50 ms where the observer's release path and the F/T's sample-and-hold disagree; a phantom
  /// lasts), beyond consistency_Nm + consistency_relative
  /// max(|t|, |tau_obs|) is a wrench nobody applies. The absolute part covers the observer's bias
  /// from model error (5 % of the link inertials on the plant); the relative part the tool's
  /// inertial forces, the sensor's calibration and a push elsewhere on the arm partly opposing
  /// J^T F (joint torques cannot tell a hand on the elbow from one on the tool: such a push, if it
  /// cancels J^T F by more than the tolerance, drops the F/T, which only costs its use).
  double consistency_filter_s = 0.15;
  double consistency_Nm = 1.5;
  double consistency_relative = 0.3;
  /// Before the drop's budget runs out, the wrench stops counting as a touch (fresh() false) once
  /// its newest changed sample is older than hold_periods x the sensor's own mean interval (at
  /// least hold_min_s): a stuck or stale hand must not keep the end effector free for stale_s. A
  /// hiccup only releases the touch (the hand's pose becomes the target; a hand still pushing
  /// touches again), so this may be tight where the drop may not.
  double hold_periods = 3.0;
  double hold_min_s = 0.003;
};

class WrenchSupervisor {
public:
  /// ConfigError on non-positive ranges or negative times.
  WrenchSupervisor(const WrenchSupervisorSettings& settings, double period_s, double observer_gain_rad_s, int nv);

  /// Checks the sample's wrench. `qd` the joint velocities, `observer_torque` the momentum
  /// observer's tau_ext (both of this, plausible, joint sample). True: a new, plausible sample to
  /// estimate from. False: no new sample, or the source is dropped (dropped() then true).
  bool check(const RobotState& state, const Eigen::VectorXd& qd, const Eigen::VectorXd& observer_torque);
  /// After the estimate: `ft_torque` = J^T F of the operator's wrench at the end effector (zero
  /// while the bias is being estimated). May drop the source (kInconsistent).
  void check_consistency(const Eigen::VectorXd& ft_torque, const Eigen::VectorXd& observer_torque);
  /// Back to kNoSignal: the next valid sample starts over (re-estimate the bias with it).
  void reset();

  WrenchStatus status() const { return status_; }
  bool dropped() const { return status_ >= WrenchStatus::kNotFinite; }
  bool usable() const { return status_ == WrenchStatus::kOk; }
  /// Usable, and its newest changed sample within the hold (see hold_periods): a touch may rest on it.
  bool fresh() const { return usable() && last_t_ - changed_at_s_ <= hold_s(); }
  /// The sensor's mean interval between changed samples [s] (the control period until measured).
  double sample_interval_s() const { return interval_s_; }
  /// Joints' stamp of the drop [s] (-1: none).
  double drop_time_s() const { return drop_time_s_; }
  /// The filtered unexplained torque u and its tolerance of the last check [N.m].
  double residual_Nm() const { return residual_; }
  double tolerance_Nm() const { return tolerance_; }
  /// The largest u / tolerance seen since the source was last (re)started.
  double max_residual_ratio() const { return max_ratio_; }
  const WrenchSupervisorSettings& settings() const { return settings_; }

private:
  void drop(WrenchStatus why, double t);
  double hold_s() const { return std::max(settings_.hold_periods * interval_s_, settings_.hold_min_s); }

  WrenchSupervisorSettings settings_;
  double observer_alpha_;     // one step of the observer's first-order lag, 1 - exp(-K_O T)
  double residual_alpha_;     // the low-pass of u
  WrenchStatus status_ = WrenchStatus::kNoSignal;
  Eigen::Matrix<double, 6, 1> previous_ = Eigen::Matrix<double, 6, 1>::Zero();  // last new sample
  std::uint32_t sequence_ = 0;
  double stamp_s_ = 0.0;         // the wrench's own stamp of the last new sample
  double fresh_at_s_ = 0.0;      // joints' stamp when the last new sample came
  double frozen_since_s_ = -1.0; // joints' stamp when the samples stopped changing (-1: changing)
  double drop_time_s_ = -1.0;
  double last_t_ = 0.0;          // joints' stamp of the last check
  double changed_at_s_ = 0.0;    // joints' stamp of the last new sample with other bits than the one before
  double interval_s_;            // mean interval between changed samples
  bool interval_known_ = false;
  double period_s_;
  Eigen::VectorXd ft_lagged_;    // J^T F through the observer's lag
  double residual_ = 0.0, tolerance_ = 0.0, max_ratio_ = 0.0;
};

}  // namespace phri
