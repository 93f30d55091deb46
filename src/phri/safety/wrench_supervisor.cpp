#include <phri/safety/wrench_supervisor.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

WrenchSupervisor::WrenchSupervisor(const WrenchSupervisorSettings& settings, double period_s, double observer_gain_rad_s,
                                   int nv)
    : settings_(settings),
      observer_alpha_(1.0 - std::exp(-observer_gain_rad_s * period_s)),
      residual_alpha_(period_s / (settings.consistency_filter_s + period_s)),
      interval_s_(period_s),
      period_s_(period_s),
      ft_lagged_(Eigen::VectorXd::Zero(nv)) {
  const WrenchSupervisorSettings& s = settings_;
  if (!(s.force_range_N > 0 && s.moment_range_Nm > 0 && s.stale_s >= period_s && s.frozen_s >= 0 &&
        s.frozen_speed_rad_s >= 0 && s.frozen_load_Nm >= 0 && s.consistency_filter_s >= 0 && s.consistency_Nm > 0 &&
        s.consistency_relative >= 0 && s.hold_periods >= 1 && s.hold_min_s >= 0 && std::isfinite(s.force_range_N + s.moment_range_Nm + s.stale_s + s.frozen_s +
                                                     s.consistency_Nm + s.consistency_relative))) {
    throw ConfigError("WrenchSupervisorSettings", "",
                      "ranges and consistency_Nm must be > 0, stale_s >= the period, the other values >= 0, all finite");
  }
  if (!(period_s > 0 && observer_gain_rad_s > 0 && nv > 0)) {
    throw ConfigError("WrenchSupervisorSettings", "", "period, observer gain and joint count must be > 0");
  }
}

void WrenchSupervisor::reset() {
  status_ = WrenchStatus::kNoSignal;
  frozen_since_s_ = -1.0;
  drop_time_s_ = -1.0;
  interval_s_ = period_s_;
  interval_known_ = false;
  ft_lagged_.setZero();
  residual_ = tolerance_ = max_ratio_ = 0.0;
}

void WrenchSupervisor::drop(WrenchStatus why, double t) {
  status_ = why;
  drop_time_s_ = t;
}

bool WrenchSupervisor::check(const RobotState& state, const Eigen::VectorXd& qd, const Eigen::VectorXd& observer_torque) {
  if (dropped()) return false;
  const double t = state.joints.stamp_s;  // the joints' clock, vetted by the StateSupervisor
  last_t_ = t;
  const SignalStatus& signal = state.wrench;
  const Eigen::Matrix<double, 6, 1>& w = state.wrench_sensor;
  if (!signal.valid) {
    // Before the first sample: no sensor, or not streaming yet (the estimate stays zero).
    if (status_ == WrenchStatus::kOk) drop(WrenchStatus::kInvalid, t);
    return false;
  }
  if (!w.allFinite()) {
    drop(WrenchStatus::kNotFinite, t);
    return false;
  }
  if (w.head<3>().cwiseAbs().maxCoeff() > settings_.force_range_N ||
      w.tail<3>().cwiseAbs().maxCoeff() > settings_.moment_range_Nm) {
    drop(WrenchStatus::kOutOfRange, t);
    return false;
  }
  if (status_ == WrenchStatus::kNoSignal) {
    status_ = WrenchStatus::kOk;
    changed_at_s_ = t;
  } else {
    // A new sample: its sequence and its own stamp (another clock than the joints' on a real
    // sensor, so only compared with itself) both advance.
    const bool advanced = static_cast<std::int32_t>(signal.sequence - sequence_) > 0 && signal.stamp_s > stamp_s_;
    if (!advanced) {
      if (t - fresh_at_s_ > settings_.stale_s) drop(WrenchStatus::kStale, t);
      return false;
    }
    // Strain gauges always carry noise: the same bits again while the arm moves or carries a load
    // is a sensor (or its driver) repeating itself.
    const bool same = (w.array() == previous_.array()).all();
    if (!same) {
      // The sensor's own rate, from the changes it delivers (a bus may repeat a sample).
      const double interval = std::min(t - changed_at_s_, settings_.stale_s);
      interval_s_ = interval_known_ ? interval_s_ + 0.1 * (interval - interval_s_) : interval;
      interval_known_ = true;
      changed_at_s_ = t;
    }
    const bool busy = qd.cwiseAbs().maxCoeff() > settings_.frozen_speed_rad_s ||
                      observer_torque.norm() > settings_.frozen_load_Nm;
    if (settings_.frozen_s > 0.0 && busy && same) {
      if (frozen_since_s_ < 0.0) frozen_since_s_ = fresh_at_s_;
      if (t - frozen_since_s_ >= settings_.frozen_s) {
        drop(WrenchStatus::kFrozen, t);
        return false;
      }
    } else {
      frozen_since_s_ = -1.0;
    }
  }
  sequence_ = signal.sequence;
  stamp_s_ = signal.stamp_s;
  fresh_at_s_ = t;
  previous_ = w;
  return true;
}

void WrenchSupervisor::check_consistency(const Eigen::VectorXd& ft_torque, const Eigen::VectorXd& observer_torque) {
  if (!usable() || ft_torque.size() != ft_lagged_.size() || observer_torque.size() != ft_lagged_.size()) return;
  // J^T F through the observer's first-order lag (pole K_O): a push then reaches both alike.
  ft_lagged_ += observer_alpha_ * (ft_torque - ft_lagged_);
  const double size = ft_lagged_.norm();
  const double seen = size > 1e-9 ? std::max(0.0, ft_lagged_.dot(observer_torque) / size) : 0.0;
  const double unexplained = std::max(0.0, size - seen);
  residual_ += residual_alpha_ * (unexplained - residual_);
  // Relative to the larger of the two: a push elsewhere on the arm (the observer's alone) that
  // partly opposes J^T F must not read as a phantom; a phantom on an arm nobody touches stands out.
  tolerance_ = settings_.consistency_Nm + settings_.consistency_relative * std::max(size, observer_torque.norm());
  max_ratio_ = std::max(max_ratio_, residual_ / tolerance_);
  if (residual_ > tolerance_) drop(WrenchStatus::kInconsistent, last_t_);
}

}  // namespace phri
