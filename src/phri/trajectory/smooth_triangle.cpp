#include <phri/trajectory/smooth_triangle.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

SmoothTriangle::SmoothTriangle(double lo, double hi, double speed, double acceleration)
    : lo_(std::min(lo, 0.0)), hi_(std::max(hi, 0.0)), speed_(speed), accel_(acceleration) {
  const double span = hi_ - lo_;
  if (!(accel_ > 0.0)) accel_ = 1.0;
  // Too short a span for the turns at this speed: slow down until the two turns fill it.
  speed_ = std::min(std::max(speed_, 0.0), std::sqrt(accel_ * span));
  if (speed_ <= 0.0) return;  // no motion
  turn_ = speed_ / accel_;
  const double d = 0.5 * speed_ * turn_;  // distance covered by one half-turn
  cruise_ = std::max(0.0, (span - 2.0 * d) / speed_);
  leg_ = 2.0 * turn_ + cruise_;
  // Where the first leg (hi -> lo) passes through 0.
  if (hi_ - d >= 0.0 && lo_ + d <= 0.0) {
    phase_ = turn_ + (hi_ - d) / speed_;
  } else if (hi_ - d < 0.0) {
    phase_ = std::sqrt(2.0 * hi_ / accel_);
  } else {
    phase_ = leg_ - std::sqrt(-2.0 * lo_ / accel_);
  }
}

void SmoothTriangle::leg(double tau, double& x, double& v, double& a) const {
  if (tau < turn_) {
    x = hi_ - 0.5 * accel_ * tau * tau;
    v = -accel_ * tau;
    a = -accel_;
  } else if (tau < turn_ + cruise_) {
    x = hi_ - 0.5 * speed_ * turn_ - speed_ * (tau - turn_);
    v = -speed_;
    a = 0.0;
  } else {
    const double r = std::max(0.0, leg_ - tau);
    x = lo_ + 0.5 * accel_ * r * r;
    v = -accel_ * r;
    a = accel_;
  }
}

void SmoothTriangle::evaluate(double t, double& x, double& v, double& a) const {
  if (leg_ <= 0.0) {
    x = v = a = 0.0;
    return;
  }
  const double tau = std::fmod(std::max(t, 0.0) + phase_, 2.0 * leg_);
  if (tau < leg_) {
    leg(tau, x, v, a);
  } else {
    leg(tau - leg_, x, v, a);  // the way back: mirror image
    x = lo_ + hi_ - x;
    v = -v;
    a = -a;
  }
}

}  // namespace phri
