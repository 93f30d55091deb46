#pragma once
// phri::StateEncoder: the dashboard's JSON, built on the server's thread (never the control
// thread's): the robot description the page draws once (GET /api/model) and one frame per loop
// snapshot (the server-sent-event stream). What the loop does not hand over is computed here
// from the snapshot's joint positions, with the encoder's own Data: body placements for the 3-D
// view, the closest self-collision pair and its distance, the push's point in the world.
//
// A frame: t, cycle, paused, q, qd_ratio (|qd| / velocity limit), margin (distance to the nearer
// joint limit / half the range, 1 at the middle, 0 at a limit), tau_d, tau_s, ee and target ({p, q}:
// position [m], quaternion w x y z), err_pos_mm, err_ori_deg, wrench (6), wrench_norm, mode,
// touched, loop, fsm, safety, event, cycle_us, overruns, gains (stiffness_scale, ee_gamma,
// posture_gamma, posture_stiffness), bodies ([x y z qw qx qy qz] per model body), push (null or
// {body, point, force, magnitude}), collision (null or {first, second, distance_mm, a, b}),
// contact_ratio (v / v_max per link of the model's `contact` list: [{link, region}], empty without
// body regions).
#include <phri/app/live_channel.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

#include <optional>
#include <string>

namespace phri {

struct StateEncoderSettings {
  double push_max_N = 100.0;
  double touch_threshold = 8.0;    ///< dual compliance, drawn on the wrench plot
  double release_threshold = 4.0;
  /// The arm's end-effector frame: no default (the dashboard server sets the controller's).
  std::string end_effector_frame;
  /// The body regions the links may meet (Config::body_regions), or none: the page then draws no
  /// power-and-force-limiting bars.
  std::optional<BodyRegionMap> body_regions;
};

class StateEncoder {
public:
  /// `collision`: null when the controller has no capsule model (no capsules drawn, no pair).
  StateEncoder(const Model& model, const CollisionModel* collision, const StateEncoderSettings& settings);

  /// The description: joints and limits, bodies, capsules, events, gains and ranges, thresholds.
  std::string model_json() const;
  /// One frame of the stream (JSON, one line).
  std::string frame_json(const LiveSnapshot& snapshot);

private:
  const Model& model_;
  const CollisionModel* collision_;
  StateEncoderSettings settings_;
  Data data_;
  std::optional<CollisionData> collision_data_;
  Eigen::VectorXd q_;
};

}  // namespace phri
