#pragma once
// The horizontal motion of the dynamic scenario: a triangle wave with rounded corners.


namespace phri {

/// Back-and-forth along one axis between lo < hi at constant speed v, turning at constant
/// acceleration a (each turn takes 2 v / a and reaches v^2 / (2 a) beyond the straight part, all
/// within [lo, hi]). Starts at 0 (lo <= 0 <= hi) moving toward lo. Needs hi - lo >= v^2 / a.
class SmoothTriangle {
public:
  SmoothTriangle() = default;
  SmoothTriangle(double lo, double hi, double speed, double acceleration);
  /// Offset, velocity, acceleration at time t >= 0.
  void evaluate(double t, double& x, double& v, double& a) const;
  double period() const { return 2.0 * leg_; }

private:
  void leg(double tau, double& x, double& v, double& a) const;  // from hi toward lo, tau in [0, leg_)
  double lo_ = 0.0, hi_ = 0.0, speed_ = 0.0, accel_ = 1.0;
  double turn_ = 0.0;    // v / a
  double cruise_ = 0.0;  // straight-part duration
  double leg_ = 0.0;     // one way
  double phase_ = 0.0;   // time within the first leg where x = 0
};

}  // namespace phri
