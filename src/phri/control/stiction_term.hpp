#pragma once
// One axis of the tasks' stiction term (PostureTask, EndEffectorTask; not in the paper): restart
// from zero when the error crosses the target; while `active` (stuck or creeping near a held
// target) integrate gain * error, clamped to +-limit; otherwise bleed off by the factor `bleed`
// (exp(-dt / tau)).
#include <algorithm>

namespace phri {

inline double stiction_step(double term, double error, bool active, double gain, double limit, double dt,
                            double bleed) {
  if (term * error < 0.0) term = 0.0;  // crossed the target: start again from the other side
  return active ? std::clamp(term + gain * error * dt, -limit, limit) : term * bleed;
}

}  // namespace phri
