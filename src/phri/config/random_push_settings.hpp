#pragma once
// phri::RandomPushSettings: the seeded random-push generator of the plant (RandomPushGenerator):
// pushes at random times on random arm links, at a random point of the link's surface (its
// collision capsule), in a random direction into the surface, with a random magnitude and
// duration. One push at a time.
#include <phri/config/external_force.hpp>

#include <string>
#include <vector>

namespace phri {

struct RandomPushSettings {
  bool enabled = false;
  std::vector<std::string> links;  ///< candidate bodies (each needs a capsule geom); empty: every arm link
  double start_s = 0.5;            ///< no push before this time [s]
  double min_interval_s = 1.0;     ///< pause between the end of a push and the next start [s]
  double max_interval_s = 3.0;
  double min_force_N = 20.0;       ///< peak force magnitude [N]
  double max_force_N = 200.0;
  double min_duration_s = 0.05;
  double max_duration_s = 0.3;
  ExternalForce::Profile profile = ExternalForce::Profile::kHalfSine;
};

}  // namespace phri
