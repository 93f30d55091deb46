#include <phri/sim/random_push_generator.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

namespace phri {

double RandomPushGenerator::Push::scale_at(double t) const {
  ExternalForce f;
  f.profile = profile;
  f.start_s = start_s;
  f.duration_s = duration_s;
  f.rise_s = 0.5 * duration_s;
  return f.scale_at(t);
}

RandomPushGenerator::RandomPushGenerator(const RandomPushSettings& settings, std::vector<LinkSurface> links,
                                         std::uint64_t seed)
    : settings_(settings), links_(std::move(links)), rng_(seed, /*stream=*/0x5055534855ULL) {
  if (enabled()) draw_next(settings_.start_s);
}

void RandomPushGenerator::draw_next(double earliest_start) {
  const auto count = static_cast<double>(links_.size());
  const auto pick = std::min(links_.size() - 1, static_cast<std::size_t>(rng_.uniform() * count));
  const LinkSurface& link = links_[pick];
  Push p;
  p.index = push_.index + 1;
  p.body = link.body;
  p.profile = settings_.profile;
  p.start_s = earliest_start;
  p.duration_s = rng_.uniform(settings_.min_duration_s, settings_.max_duration_s);
  p.peak_force_N = rng_.uniform(settings_.min_force_N, settings_.max_force_N);

  // Point: uniform along the segment, radial direction uniform around the axis.
  const Eigen::Vector3d axis_vec = link.p1 - link.p0;
  const double length = axis_vec.norm();
  const Eigen::Vector3d axis = length > 1e-12 ? Eigen::Vector3d(axis_vec / length) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d helper = std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = axis.cross(helper).normalized();
  const Eigen::Vector3d e2 = axis.cross(e1);
  const double along = rng_.uniform();
  const double phi = 2.0 * std::numbers::pi * rng_.uniform();
  const Eigen::Vector3d normal = std::cos(phi) * e1 + std::sin(phi) * e2;  // outward
  p.point_local = link.p0 + along * axis_vec + link.radius * normal;

  // Direction: uniform on the sphere (normalised Gaussian triple), flipped into the surface.
  Eigen::Vector3d d(rng_.normal(), rng_.normal(), rng_.normal());
  if (d.norm() < 1e-12) d = -normal;
  d.normalize();
  if (d.dot(normal) > 0.0) d = -d;
  p.direction_local = d;
  push_ = p;
}

const RandomPushGenerator::Push* RandomPushGenerator::active(double t) {
  if (!enabled()) return nullptr;
  while (t >= push_.start_s + push_.duration_s) {
    draw_next(push_.start_s + push_.duration_s + rng_.uniform(settings_.min_interval_s, settings_.max_interval_s));
  }
  return t >= push_.start_s ? &push_ : nullptr;
}

}  // namespace phri
