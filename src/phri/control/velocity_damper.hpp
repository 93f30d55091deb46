#pragma once
// The paper's second-order velocity damper (section "Safety Features", eq. sec-order-vel-damp),
// the one function behind the joint-limit and self-collision constraints. For a distance e to a
// limit (e >= d_s wanted) it bounds the distance's second derivative from below:
//
//   ë >= -lambda^2 / (4 M^2) (e - d_s) - lambda ė,    lambda = 4 M^2 xi / (d_i - d_s)
//
// M > 1 makes it overdamped (the distance never undershoots d_s); xi is the approach speed the
// damper still allows at the influence distance d_i. (mc_rtc: `damper{iDist, sDist, damping}`.)
namespace phri {

struct VelocityDamperSettings {
  double influence_distance = 0.0;  ///< d_i (rad for joints, m for distances)
  double safety_distance = 0.0;     ///< d_s < d_i
  double xi = 0.0;                  ///< approach speed allowed at d_i (rad/s or m/s)
  double amortization = 1.8;        ///< M > 1 (paper's demo value 1.8)
  double lambda() const { return 4.0 * amortization * amortization * xi / (influence_distance - safety_distance); }
};

class VelocityDamper {
public:
  VelocityDamper() = default;
  explicit VelocityDamper(const VelocityDamperSettings& s)
      : safety_distance_(s.safety_distance),
        lambda_(s.lambda()),
        stiffness_(lambda_ * lambda_ / (4.0 * s.amortization * s.amortization)) {}

  /// The lowest ë allowed at distance e moving at ė.
  double min_acceleration(double e, double e_dot) const { return -stiffness_ * (e - safety_distance_) - lambda_ * e_dot; }
  double lambda() const { return lambda_; }
  double stiffness() const { return stiffness_; }  ///< lambda^2 / (4 M^2)

private:
  double safety_distance_ = 0.0;
  double lambda_ = 0.0;
  double stiffness_ = 0.0;
};

}  // namespace phri
