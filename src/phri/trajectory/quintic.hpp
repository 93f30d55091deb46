#pragma once
// Minimum-jerk time scaling, the shape of every move of the FSM (trajectory module: reference
// generators, pure functions of time, allocation-free once constructed).
#include <algorithm>

namespace phri {

/// Minimum-jerk (quintic) time scaling: s(0) = 0, s(1) = 1, zero velocity and acceleration at
/// both ends. Returns s, ds/dtau, d2s/dtau2 for tau in [0, 1] (clamped).
struct Quintic {
  double s = 0.0, ds = 0.0, dds = 0.0;
  static Quintic at(double tau) {
    tau = std::clamp(tau, 0.0, 1.0);
    const double t2 = tau * tau, t3 = t2 * tau;
    Quintic q;
    q.s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
    q.ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
    q.dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
    return q;
  }
  static constexpr double kPeakRate = 1.875;  ///< max ds/dtau
};

}  // namespace phri
