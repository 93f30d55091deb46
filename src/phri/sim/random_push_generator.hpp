#pragma once
// phri::RandomPushGenerator: draws the pushes of RandomPushSettings from a seeded
// RandomGenerator, lazily, as simulated time advances (deterministic for a given seed).
// The geometry of each candidate link is a capsule (segment p0-p1 in the body frame, radius):
// the push point is uniform along the segment, on the surface in a uniform radial direction;
// the force direction is uniform on the half-sphere pointing into the surface.
#include <phri/core/random_generator.hpp>
#include <phri/config/external_force.hpp>
#include <phri/config/random_push_settings.hpp>

#include <Eigen/Core>

#include <vector>

namespace phri {

class RandomPushGenerator {
public:
  struct LinkSurface {
    int body = -1;  ///< simulator body index, copied into the pushes
    Eigen::Vector3d p0 = Eigen::Vector3d::Zero();  ///< capsule segment in the body frame [m]
    Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
    double radius = 0.0;
  };
  struct Push {
    int body = -1;
    Eigen::Vector3d point_local = Eigen::Vector3d::Zero();      ///< on the capsule surface, body frame
    Eigen::Vector3d direction_local = Eigen::Vector3d::Zero();  ///< unit, body frame, into the surface
    double peak_force_N = 0.0;
    double start_s = 0.0;
    double duration_s = 0.0;
    ExternalForce::Profile profile = ExternalForce::Profile::kHalfSine;
    std::uint32_t index = 0;  ///< 1 for the first push

    double scale_at(double t) const;
  };

  RandomPushGenerator() = default;
  RandomPushGenerator(const RandomPushSettings& settings, std::vector<LinkSurface> links, std::uint64_t seed);

  /// The push active at time t (non-decreasing t between calls), or nullptr. No allocation.
  const Push* active(double t);
  /// The latest push drawn so far (index 0 if none yet).
  const Push& latest() const { return push_; }
  bool enabled() const { return settings_.enabled && !links_.empty(); }

private:
  void draw_next(double earliest_start);

  RandomPushSettings settings_;
  std::vector<LinkSurface> links_;
  RandomGenerator rng_;
  Push push_;
};

}  // namespace phri
