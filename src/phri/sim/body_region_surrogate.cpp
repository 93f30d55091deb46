#include <phri/sim/body_region_surrogate.hpp>

#include <algorithm>

namespace phri {

void BodyRegionSurrogate::reset() {
  displacement_ = velocity_ = compression_ = previous_compression_ = force_ = 0.0;
  touching_ = false;
}

double BodyRegionSurrogate::step(double depth_m, bool over_face, double dt) {
  compression_ = depth_m - displacement_;
  const bool touching = over_face && compression_ > 0.0 && (touching_ || previous_compression_ <= 0.0);
  if (touching) {
    // The damper acts from the second step of a contact on (its rate needs a previous compression).
    const double rate = touching_ ? (compression_ - previous_compression_) / dt : 0.0;
    force_ = std::max(0.0, settings_.stiffness_N_per_m * compression_ + settings_.damping_Ns_per_m * rate);
    touching_ = true;
  } else {
    force_ = 0.0;
    touching_ = false;
  }
  previous_compression_ = compression_;
  if (!settings_.backed_by_wall) {
    velocity_ += force_ / settings_.mass_kg * dt;  // semi-implicit Euler: velocity first
    displacement_ += velocity_ * dt;
  }
  return force_;
}

}  // namespace phri
