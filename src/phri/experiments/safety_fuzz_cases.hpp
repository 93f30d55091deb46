#pragma once
// The disturbances of the safety-fuzz experiment (safety_fuzz.hpp): the pushes (random, toward a
// joint limit, folding the wrist onto the base) and the catalogue of sensor faults, each drawn
// from the experiment's seed so that any case can be run again alone.
#include <phri/core/random_generator.hpp>
#include <phri/experiments/fault_injecting_robot.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>
#include <phri/config/external_force.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace phri {

enum class PushKind : std::uint8_t { kRandom = 0, kJointLimit, kWristFold };

constexpr std::string_view to_string(ExternalForce::Profile p) {
  switch (p) {
    case ExternalForce::Profile::kStep: return "step";
    case ExternalForce::Profile::kRamp: return "ramp";
    case ExternalForce::Profile::kHalfSine: return "half_sine";
  }
  return "unknown";
}

/// One push on the arm: a force at a point of a link, with a time profile (relative start 0).
struct PushSpec {
  PushKind kind = PushKind::kRandom;
  int body = -1;                 ///< the controller model's body the link moves with
  std::string link;              ///< its name (the plant's MJCF body of the same name)
  Eigen::Vector3d point_local = Eigen::Vector3d::Zero();  ///< in the body frame [m]
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();      ///< full scale, body axes (random) or world axes
  bool local_frame = true;
  double magnitude_N = 0.0;
  ExternalForce::Profile profile = ExternalForce::Profile::kStep;
  double duration_s = 0.0;
  double rise_s = 0.0;           ///< kRamp
  int joint = -1;                ///< kJointLimit: the joint (0-based)
  int toward = 0;                ///< kJointLimit: +1 its upper limit, -1 its lower one
  /// Non-empty: the plant's body the force lands on when it is not `link` (a hand on the tool below
  /// the F/T sensor), at plant_point_local of that body; `body` and `point_local` then say where
  /// that point is on the controller's model (for the required-torque check), and the force is in
  /// world axes.
  std::string plant_body;
  Eigen::Vector3d plant_point_local = Eigen::Vector3d::Zero();

  /// The plant's body name the force is applied to.
  const std::string& plant_link() const { return plant_body.empty() ? link : plant_body; }

  /// The plant disturbance, starting at `start_s` (its body name left empty: SimRobot::set_live_disturbance).
  ExternalForce disturbance(double start_s) const;
};

/// Ranges of the random pushes (the numbers).
struct RandomPushRanges {
  double min_force_N = 0.0, max_force_N = 200.0;
  double min_duration_s = 0.05, max_duration_s = 2.0;
};

/// The name of the link a model body stands for (its own frame's name).
std::string body_link_name(const Model& model, int body);

/// A random push: a capsule of `collision` on a moving link, a uniform point of its surface, a
/// direction uniform on the half-sphere into the surface (body axes), a uniform magnitude, profile
/// and duration (a ramp rises over a uniform part of the duration).
PushSpec draw_random_push(RandomGenerator& rng, const Model& model, const CollisionModel& collision,
                          const RandomPushRanges& ranges);

/// A sustained push of `force_N` for `duration_s` (50 ms ramp) that drives joint `joint` toward its
/// upper (toward = +1) or lower limit: at the origin of the body after the joint's child (the far
/// end of the moving link), along ± that point's Jacobian column of the joint, from `data` (kinematics
/// of the pose where it starts). kind kJointLimit; body -1 when the column vanishes there.
PushSpec joint_limit_push(const Model& model, const Data& data, int joint, int toward, double force_N, double duration_s);

/// A push folding the wrist onto the base: at the origin of `link`, toward `target` (world), as
/// tests/test_sim_control.cpp SelfCollisionDamperKeepsTheWristOffTheBase does. kind kWristFold.
PushSpec wrist_fold_push(const Model& model, const Data& data, const std::string& link, const Eigen::Vector3d& target,
                         double force_N, double duration_s);

/// The pushes and fault times of the fault-in-motion windows (safety_fuzz.hpp; the numbers).
struct MotionFaultRanges {
  double min_force_N = 20.0, max_force_N = 80.0;       ///< the push: a ramp to this force
  double min_duration_s = 1.0, max_duration_s = 2.0;   ///< and this long
  double min_fault_start_s = 0.1, max_fault_start_s = 0.5;  ///< the fault (or the loop switch) after the push began
  double max_switch_delay_s = 0.05;                    ///< the fault after the loop switch
};

/// The push of a fault-in-motion window: a ramp (rising over a uniform 10-100 % of its duration) to a
/// uniform magnitude in the ranges, for a uniform duration; on a random moving link's capsule as
/// draw_random_push, or, with `hand_on_tool` (dual compliance, so that its trigger engages), on the
/// plant's body `tool_body` at its origin (the F/T sensor's measuring frame: the sensor feels it),
/// along a direction uniform on the sphere (world axes); `tool_frame` is the controller model's frame
/// at that origin (for the required-torque check).
PushSpec draw_motion_push(RandomGenerator& rng, const Model& model, const CollisionModel& collision,
                          const MotionFaultRanges& ranges, bool hand_on_tool, const std::string& tool_body,
                          const std::string& tool_frame);

/// FNV-1a of a name: a seed stream per fault case that does not depend on the catalogue's order.
std::uint64_t name_hash(std::string_view name);

/// Which sensor faults to inject.
enum class FaultSet : std::uint8_t { kNone = 0, kSubset, kAll };

/// One entry of the catalogue: its name and the fault (start_cycle and cycles set by the runner).
struct FaultCase {
  std::string name;
  FaultSpec spec;
  /// > 0: the fault's own length in reads, at rest and in motion (a stall: 1 read, its length is its
  /// value; a one-sample jump: 1; a held offset or a drift: 100); 0: at rest each of the options'
  /// fault_cycles, in motion `motion_cycles`.
  long fixed_cycles = 0;
  long motion_cycles = 100;  ///< in motion when fixed_cycles is 0: spikes 1, sustained faults 100

  /// The length of the window in motion.
  long cycles_in_motion() const { return fixed_cycles > 0 ? fixed_cycles : motion_cycles; }
};

/// The catalogue (see safety_fuzz.hpp): NaN, inf, ±1e6 spikes on q, q̇, τ_s and current; moderate
/// spikes (+0.5 rad, +3 rad/s, +50 N.m); offsets; frozen values; a stale frame; sequence and stamp
/// jumps; frozen stamps; short current vectors; F/T spikes and NaN; refused writes; then control-thread
/// stalls of 19, 20, 50 and a random 1-100 periods, a +1e6 sequence jump (one sample), a 50 N.m
/// torque-sensor offset held for 100 cycles and a 0 -> 50 N.m torque drift over 100 cycles, and the
/// F/T wrench stuck, stale and invalid. The joint of each per-joint fault, the sign of the 1e6 spikes
/// and the random stall are drawn from `seed` (the new entries after the older ones: their draws are
/// unchanged). kSubset: eight of them.
std::vector<FaultCase> fault_catalogue(FaultSet set, int dof, std::uint64_t seed);

/// splitmix64 of (a, b): independent seeds for runs and cases from the experiment's seed.
std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b);

}  // namespace phri
