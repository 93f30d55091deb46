#include <phri/experiments/collision.hpp>

#include <phri/config/config.hpp>
#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/parallel_runs.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/trajectory/dynamic_trajectory.hpp>
#include <phri/trajectory/pose_move.hpp>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

// Where the face rests until the run places it on the path: far below the arm.
const Eigen::Vector3d kParkedFace(0.0, 0.0, -100.0);

SimRobotConfig collision_plant(const CollisionOptions& o, const BodyRegion& region, bool clamped) {
  SimRobotConfig c = SimRobotConfig::from_yaml_file(o.plant_config_path);
  if (static_cast<int>(o.start_q_rad.size()) != c.dof()) {
    throw ConfigError("<collision options>", "start_q_rad", "needs one value per joint");
  }
  c.initial_q_rad = o.start_q_rad;
  c.seed = o.seed;
  c.mismatch.enabled = true;  // the controller's model is not the plant's
  c.surrogate.enabled = true;
  c.surrogate.region = {region.mass_kg, region.stiffness_N_per_m, 0.0, clamped};
  c.surrogate.face_m = kParkedFace;
  return c;
}

ControllerSettings collision_settings(const CollisionOptions& o, const SimRobotConfig& plant, const CollisionRun& c) {
  ControllerSettings s;
  s.urdf_path = o.urdf_path;
  s.actuators_path = o.actuators_path;
  s.collision_path = o.collision_path;
  s.end_effector_frame = o.end_effector_frame;
  s.set_end_of_arm(plant.end_of_arm());
  s.initial_compliance = c.mode;
  s.initial_loop = LowLevelMode::kPosition;
  if (c.constraint) {
    PowerForceLimitSettings limit;
    limit.regions.region = c.region;  // a person may be met by any link
    s.qp.power_force_limit = limit;
  }
  return s;
}

// One recorded cycle around the touch.
struct TraceRow {
  double t_s, force_N, compression_m, speed_m_s, tool_ratio, worst_ratio;
};

class CollisionTrial {
public:
  CollisionTrial(const CollisionOptions& options, const CollisionRun& what)
      : o_(options), run_(what), plant_(collision_plant(options, what.region, what.clamped)), robot_(plant_),
        cycle_(collision_settings(options, plant_, what)), command_(robot_.dof()), targets_(robot_.dof()),
        truth_(cycle_.model()), dt_(robot_.period_s()) {
    Eigen::VectorXd rotor(robot_.dof());
    for (int i = 0; i < robot_.dof(); ++i) rotor[i] = cycle_.actuators()[i].reflected_inertia_kgm2;
    if (!cycle_.collision()) throw ExperimentError("collision", "the controller has no capsules to judge the links by");
    BodyRegionMap map;
    map.region = what.region;
    monitor_.emplace(cycle_.model(), *cycle_.collision(), rotor, map);
    tool_link_ = -1;
    for (int i = 0; i < monitor_->num_links(); ++i) {
      if (monitor_->link_name(i) == o_.end_effector_frame) tool_link_ = i;
    }
    run_.link_max_ratio.assign(static_cast<std::size_t>(monitor_->num_links()), 0.0);
  }

  CollisionRun run(std::vector<TraceRow>& trace) {
    start_up();
    const Eigen::Isometry3d start = cycle_.qp().end_effector().target_pose();
    const Eigen::Vector3d ee = true_position();
    if (run_.motion == CollisionMotion::kPointToPoint) {
      point_to_point(start, ee, trace);
    } else {
      dynamic(start, ee, trace);
    }
    finish();
    return run_;
  }

  std::vector<std::string> link_names() const {
    std::vector<std::string> names;
    for (int i = 0; i < monitor_->num_links(); ++i) names.push_back(monitor_->link_name(i));
    return names;
  }

private:
  Eigen::Vector3d true_position() {
    forward_kinematics(cycle_.model(), truth_, robot_.truth().q_rad);
    update_frame_placements(cycle_.model(), truth_);
    return truth_.frame_placements[static_cast<std::size_t>(cycle_.end_effector_frame())].translation();
  }

  void step() {
    const RobotState& state = robot_.read();
    if (state.fault) throw ExperimentError("collision", "the simulated plant faulted");
    const CycleStatus status = cycle_.step(state, targets_, command_);
    targets_.clear();
    const bool refused = robot_.write(command_) != WriteStatus::kOk;
    t_ += dt_;
    if (!measuring_) return;
    const double force = robot_.truth().surrogate_peak_force_N;
    if (!touched_ && force > 0.0) touch();
    if (!touched_) {
      // Until the touch the run must be what it names.
      if (status != CycleStatus::kOk && bad_++ == 0) first_bad_ = status;
      if (cycle_.low_level().loop() != run_.loop) ++other_loop_;
      if (cycle_.compliance().mode() != run_.mode) ++other_mode_;
      if (refused) ++refused_;
      judge_links();
    } else {
      if (status != CycleStatus::kOk && reaction_status_ == CycleStatus::kOk) {
        reaction_status_ = status;
        reaction_after_ = t_ - run_.contact_time_s;
      }
      if (cycle_.compliance().touched() && !released_) {
        released_ = true;
        released_after_ = t_ - run_.contact_time_s;
      }
      const double after = t_ - run_.contact_time_s;
      if (force > run_.peak_force_N) {
        run_.peak_force_N = force;
        run_.peak_after_s = after;
      }
      if (force > run_.limit_N()) run_.time_above_limit_s += dt_;
      if (force > 0.0) run_.contact_duration_s = after + dt_;
      if (after >= o_.contact_window_s - o_.quasi_static_window_s) {
        quasi_static_sum_ += robot_.truth().surrogate_force_N;
        ++quasi_static_count_;
      }
    }
  }

  // Every link's v / v_max this cycle, on the true state.
  void update_monitor() {
    compute_all_terms(cycle_.model(), truth_, robot_.truth().q_rad, robot_.truth().qd_rad_s);
    monitor_->update(cycle_.model(), truth_);
  }

  // ... and their largest before the touch.
  void judge_links() {
    update_monitor();
    for (int i = 0; i < monitor_->num_links(); ++i) {
      double& m = run_.link_max_ratio[static_cast<std::size_t>(i)];
      m = std::max(m, monitor_->link(i).ratio());
    }
    if (tool_link_ >= 0) run_.max_tool_ratio = std::max(run_.max_tool_ratio, monitor_->link(tool_link_).ratio());
  }

  void touch() {
    touched_ = true;
    run_.contact_time_s = t_;
    run_.approach_speed_m_s = robot_.tool_velocity().dot(-normal_);
    update_monitor();
    if (tool_link_ >= 0) {
      run_.reflected_mass_kg = monitor_->link(tool_link_).reflected_mass_kg;
      run_.permissible_speed_m_s = monitor_->link(tool_link_).permissible_speed_m_s;
    }
  }

  void start_up() {
    while (t_ < o_.switch_s) step();
    if (run_.loop != LowLevelMode::kPosition) targets_.low_level_mode = run_.loop;
    while (t_ < o_.switch_s + o_.settle_s) step();
    measuring_ = true;
  }

  void place_face(const Eigen::Vector3d& tool_point, const Eigen::Vector3d& motion) {
    normal_ = -motion.normalized();
    robot_.set_surrogate_face(tool_point, normal_);
  }

  // Steps until the window after the touch has passed, or `deadline` without a touch.
  template <class Reference>
  void drive(double deadline, std::vector<TraceRow>& trace, Reference&& reference) {
    while (touched_ ? t_ - run_.contact_time_s < o_.contact_window_s : t_ < deadline) {
      reference(targets_);
      step();
      record(trace);
    }
  }

  void record(std::vector<TraceRow>& trace) {
    if (!touched_) {
      pre_touch_.push_back(row());
      if (pre_touch_.size() > 100) pre_touch_.erase(pre_touch_.begin());
      return;
    }
    if (!pre_touch_.empty()) {
      trace.insert(trace.end(), pre_touch_.begin(), pre_touch_.end());
      pre_touch_.clear();
    }
    trace.push_back(row());
  }

  TraceRow row() {
    if (touched_) update_monitor();  // the figures after the touch, for the trace only
    const auto& truth = robot_.truth();
    return {t_, truth.surrogate_peak_force_N, truth.surrogate_compression_m, robot_.tool_velocity().dot(-normal_),
            tool_link_ >= 0 ? monitor_->link(tool_link_).ratio() : 0.0,
            monitor_->worst_link() >= 0 ? monitor_->link(monitor_->worst_link()).ratio() : 0.0};
  }

  void point_to_point(const Eigen::Isometry3d& start, const Eigen::Vector3d& ee, std::vector<TraceRow>& trace) {
    const Eigen::Vector3d d = o_.direction.normalized();
    Eigen::Isometry3d goal = start;
    goal.translation() += o_.path_length_m * d;
    // The tool's leading point where the line's speed peaks (its middle); the orientation is held,
    // so that point keeps its offset from the end-effector frame.
    place_face(robot_.tool_point_along(d) - ee + start.translation() + 0.5 * o_.path_length_m * d, d);
    PoseMove move;
    move.start(start, goal, run_.nominal_speed_m_s, 0.5, 0.2);
    const double t0 = t_;
    drive(t0 + move.duration() + o_.contact_window_s, trace, [&](ControllerTargets& targets) {
      targets.has_pose = true;
      move.evaluate(std::min(t_ - t0, move.duration()), targets.pose);
    });
  }

  void dynamic(const Eigen::Isometry3d& start, const Eigen::Vector3d& ee, std::vector<TraceRow>& trace) {
    DynamicTrajectory trajectory;
    trajectory.start(start);
    // Where the reference is fastest in its first period after the ramp.
    const double period = 2.0 * M_PI / trajectory.settings().vertical_angular_frequency_rad_s;
    PoseReference p, fastest;
    double best = -1.0;
    for (double s = trajectory.settings().ramp_s; s < trajectory.settings().ramp_s + period; s += dt_) {
      trajectory.evaluate(s, p);
      if (p.velocity.head<3>().norm() > best) {
        best = p.velocity.head<3>().norm();
        fastest = p;
      }
    }
    run_.nominal_speed_m_s = best;
    const Eigen::Vector3d d = fastest.velocity.head<3>().normalized();
    place_face(robot_.tool_point_along(d) - ee + fastest.pose.translation(), d);
    const double t0 = t_;
    drive(t0 + trajectory.settings().ramp_s + 2.0 * period, trace, [&](ControllerTargets& targets) {
      targets.has_pose = true;
      trajectory.evaluate(t_ - t0, targets.pose);
    });
  }

  void finish() {
    std::ostringstream why;
    if (!touched_) why << "the tool never touched the region; ";
    if (other_loop_ > 0) why << other_loop_ << " cycles before the touch not in the " << to_string(run_.loop) << " loop; ";
    if (other_mode_ > 0) why << other_mode_ << " cycles before the touch not in " << to_string(run_.mode) << " mode; ";
    if (bad_ > 0) why << bad_ << " cycles before the touch not ok (first: " << to_string(first_bad_) << "); ";
    if (refused_ > 0) why << refused_ << " refused writes before the touch; ";
    run_.invalid_reason = why.str();
    if (!run_.invalid_reason.empty()) run_.invalid_reason.resize(run_.invalid_reason.size() - 2);
    run_.valid = run_.invalid_reason.empty();
    if (quasi_static_count_ > 0) run_.quasi_static_force_N = quasi_static_sum_ / quasi_static_count_;
    std::ostringstream reaction;
    if (reaction_status_ != CycleStatus::kOk) {
      reaction << to_string(reaction_status_) << " after " << format_fixed(1e3 * reaction_after_, 0) << " ms";
    }
    if (released_) {
      reaction << (reaction.tellp() > 0 ? "; " : "") << "end effector freed after " << format_fixed(1e3 * released_after_, 0)
               << " ms";
    }
    run_.reaction = reaction.tellp() > 0 ? reaction.str() : "none";
  }

  const CollisionOptions& o_;
  CollisionRun run_;
  SimRobotConfig plant_;
  SimRobot robot_;
  Controller cycle_;
  RobotCommand command_;
  ControllerTargets targets_;
  Data truth_;
  std::optional<PowerForceLimitMonitor> monitor_;
  int tool_link_ = -1;
  double dt_;
  double t_ = 0.0;
  Eigen::Vector3d normal_ = Eigen::Vector3d::UnitX();
  bool measuring_ = false, touched_ = false, released_ = false;
  long bad_ = 0, other_loop_ = 0, other_mode_ = 0, refused_ = 0;
  CycleStatus first_bad_ = CycleStatus::kOk, reaction_status_ = CycleStatus::kOk;
  double reaction_after_ = 0.0, released_after_ = 0.0;
  double quasi_static_sum_ = 0.0;
  long quasi_static_count_ = 0;
  std::vector<TraceRow> pre_touch_;
};

std::vector<CollisionRun> collision_cases(const CollisionOptions& o, const std::vector<BodyRegion>& regions) {
  std::vector<CollisionRun> cases;
  std::vector<std::pair<CollisionMotion, double>> motions;
  for (double v : o.speeds_m_s) motions.emplace_back(CollisionMotion::kPointToPoint, v);
  if (o.dynamic) motions.emplace_back(CollisionMotion::kDynamic, 0.0);
  for (const BodyRegion& region : regions) {
    for (const auto& [motion, speed] : motions) {
      for (bool clamped : {false, true}) {
        for (ComplianceMode mode : o.modes) {
          for (LowLevelMode loop : o.loops) {
            for (bool constraint : {false, true}) {
              CollisionRun c;
              c.region = region;
              c.motion = motion;
              c.nominal_speed_m_s = speed;
              c.clamped = clamped;
              c.mode = mode;
              c.loop = loop;
              c.constraint = constraint;
              cases.push_back(c);
            }
          }
        }
      }
    }
  }
  return cases;
}

std::string run_label(const CollisionRun& r) {
  std::ostringstream s;
  s << r.region.name << '/' << to_string(r.motion);
  if (r.motion == CollisionMotion::kPointToPoint) s << '_' << format_fixed(r.nominal_speed_m_s, 2);
  s << '/' << (r.clamped ? "clamped" : "free") << '/' << to_string(r.mode) << '/' << to_string(r.loop) << '/'
    << (r.constraint ? "limited" : "unlimited");
  return s.str();
}

std::string runs_csv(const CollisionResult& r) {
  std::ostringstream out;
  out << "run,region,motion,nominal_speed_m_s,contact,mode,loop,constraint,valid,approach_speed_m_s,reflected_mass_kg,"
         "permissible_speed_m_s,peak_force_N,peak_after_s,limit_N,quasi_static_force_N,quasi_static_limit_N,"
         "time_above_limit_s,contact_duration_s,max_tool_ratio,reaction,invalid_reason\n";
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const CollisionRun& c = r.runs[i];
    out << i << ',' << c.region.name << ',' << to_string(c.motion) << ',' << format_fixed(c.nominal_speed_m_s, 3) << ','
        << (c.clamped ? "clamped" : "free") << ',' << to_string(c.mode) << ',' << to_string(c.loop) << ','
        << (c.constraint ? 1 : 0) << ',' << (c.valid ? 1 : 0) << ',' << format_fixed(c.approach_speed_m_s, 4) << ','
        << format_fixed(c.reflected_mass_kg, 4) << ',' << format_fixed(c.permissible_speed_m_s, 4) << ','
        << format_fixed(c.peak_force_N, 2) << ',' << format_fixed(c.peak_after_s, 4) << ',' << format_fixed(c.limit_N(), 1)
        << ',' << format_fixed(c.quasi_static_force_N, 2) << ',' << format_fixed(c.region.quasi_static_force_N, 1) << ','
        << format_fixed(c.time_above_limit_s, 3) << ',' << format_fixed(c.contact_duration_s, 3) << ','
        << format_fixed(c.max_tool_ratio, 4) << ",\"" << c.reaction << "\",\"" << c.invalid_reason << "\"\n";
  }
  return out.str();
}

std::string links_csv(const CollisionResult& r) {
  std::ostringstream out;
  out << "run,link,max_ratio\n";
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    for (std::size_t l = 0; l < r.links.size() && l < r.runs[i].link_max_ratio.size(); ++l) {
      out << i << ',' << r.links[l] << ',' << format_fixed(r.runs[i].link_max_ratio[l], 4) << '\n';
    }
  }
  return out.str();
}

std::string trace_csv(const std::vector<std::vector<TraceRow>>& traces, const CollisionResult& r) {
  std::ostringstream out;
  out << "run,t_after_touch_s,force_N,compression_mm,speed_m_s,tool_ratio,worst_ratio\n";
  for (std::size_t i = 0; i < traces.size(); ++i) {
    for (const TraceRow& row : traces[i]) {
      out << i << ',' << format_fixed(row.t_s - r.runs[i].contact_time_s, 4) << ',' << format_fixed(row.force_N, 2) << ','
          << format_fixed(1e3 * row.compression_m, 3) << ',' << format_fixed(row.speed_m_s, 4) << ','
          << format_fixed(row.tool_ratio, 4) << ',' << format_fixed(row.worst_ratio, 4) << '\n';
    }
  }
  return out.str();
}

// Per compliance mode and loop, the worst over regions and motions: the reaction is the controller's.
std::string mode_loop_table(const CollisionResult& r) {
  std::ostringstream s;
  s << "Per compliance mode and loop (worst over regions and motions, valid runs; unlimited / limited):\n\n"
    << "| mode | loop | peak free [N] | peak clamped [N] | clamping force [N] | longest time above F_QS clamped [s] | "
       "contact ended within the window (clamped) | reactions |\n|---|---|---|---|---|---|---|---|\n";
  const CollisionOptions& o = r.options;
  for (ComplianceMode mode : o.modes) {
    for (LowLevelMode loop : o.loops) {
      double free_peak[2] = {0, 0}, clamp_peak[2] = {0, 0}, clamp_force[2] = {0, 0}, above[2] = {0, 0};
      int released[2] = {0, 0}, clamped_runs[2] = {0, 0};
      std::vector<std::string> reactions;
      for (const CollisionRun& c : r.runs) {
        if (c.mode != mode || c.loop != loop || !c.valid) continue;
        const int w = c.constraint ? 1 : 0;
        if (!c.clamped) {
          free_peak[w] = std::max(free_peak[w], c.peak_force_N);
          continue;
        }
        clamp_peak[w] = std::max(clamp_peak[w], c.peak_force_N);
        clamp_force[w] = std::max(clamp_force[w], c.quasi_static_force_N);
        above[w] = std::max(above[w], c.time_above_limit_s);  // clamped: the limit is F_QS
        ++clamped_runs[w];
        if (c.contact_duration_s < o.contact_window_s - 1e-9) ++released[w];
        const std::string kind = c.reaction.substr(0, c.reaction.find(" after"));
        if (std::find(reactions.begin(), reactions.end(), kind) == reactions.end()) reactions.push_back(kind);
      }
      auto pair = [](const double v[2], int digits) { return format_fixed(v[0], digits) + " / " + format_fixed(v[1], digits); };
      s << "| " << to_string(mode) << " | " << to_string(loop) << " | " << pair(free_peak, 0) << " | " << pair(clamp_peak, 0)
        << " | " << pair(clamp_force, 0) << " | " << pair(above, 2) << " | " << released[0] << " of " << clamped_runs[0]
        << " / " << released[1] << " of " << clamped_runs[1] << " | ";
      for (std::size_t i = 0; i < reactions.size(); ++i) s << (i ? ", " : "") << reactions[i];
      s << " |\n";
    }
  }
  return s.str();
}

}  // namespace

std::vector<BodyRegion> collision_regions(const CollisionOptions& o) {
  if (o.regions.empty()) throw ConfigError("<collision options>", "regions", "name at least one region");
  if (o.modes.empty() || o.loops.empty()) throw ConfigError("<collision options>", "modes/loops", "name at least one of each");
  if (o.speeds_m_s.empty() && !o.dynamic) throw ConfigError("<collision options>", "speeds_m_s", "no motion to run");
  for (double v : o.speeds_m_s) {
    if (!(v > 0.0) || !std::isfinite(v)) throw ConfigError("<collision options>", "speeds_m_s", "speeds must be > 0");
  }
  if (!(o.path_length_m > 0.0) || !(o.direction.norm() > 0.0) || !(o.contact_window_s > o.quasi_static_window_s) ||
      !(o.quasi_static_window_s > 0.0)) {
    throw ConfigError("<collision options>", "path_length_m/direction/contact_window_s",
                      "need a path > 0, a direction and a window longer than the quasi-static one (> 0)");
  }
  std::vector<BodyRegion> regions;
  for (const std::string& name : o.regions) regions.push_back(body_region_from_file(o.regions_file, name));
  return regions;
}

CollisionResult run_collision(const CollisionOptions& o, std::ostream* progress) {
  const std::vector<BodyRegion> regions = collision_regions(o);
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  CollisionResult r;
  r.options = o;
  r.runs = collision_cases(o, regions);
  std::vector<std::vector<TraceRow>> traces(r.runs.size());
  std::mutex print;
  int done = 0;
  run_in_parallel(static_cast<int>(r.runs.size()), o.jobs, [&](int i) {
    const auto k = static_cast<std::size_t>(i);
    CollisionTrial trial(o, r.runs[k]);
    std::vector<TraceRow> trace;
    const CollisionRun run = trial.run(trace);
    const std::lock_guard<std::mutex> lock(print);
    r.runs[k] = run;
    traces[k] = std::move(trace);
    if (r.links.empty()) r.links = trial.link_names();
    ++done;
    if (progress && (done % 12 == 0 || done == static_cast<int>(r.runs.size()))) {
      *progress << "  " << done << " / " << r.runs.size() << " collisions (last: " << run_label(run) << ", peak "
                << format_fixed(run.peak_force_N, 0) << " N)" << std::endl;
    }
  });
  if (!o.output_dir.empty()) {
    r.files = write_output_files(o.output_dir, {{"collision_runs.csv", runs_csv(r)},
                                                {"collision_links.csv", links_csv(r)},
                                                {"collision_trace.csv", trace_csv(traces, r)},
                                                {"collision.md", collision_table(r)}});
  }
  return r;
}

namespace {

// The runs of one region, motion (and speed) and contact, without [0] and with [1] the constraint.
struct CollisionGroup {
  const CollisionRun* first = nullptr;
  double speed[2] = {0, 0}, vmax = 1e9, peak[2] = {0, 0}, clamp[2] = {0, 0};
  int over[2] = {0, 0}, count[2] = {0, 0}, invalid = 0;
};

bool over_limit(const CollisionRun& c) {
  return c.peak_force_N > c.limit_N() || (c.clamped && c.quasi_static_force_N > c.region.quasi_static_force_N);
}

std::vector<CollisionGroup> collision_groups(const CollisionResult& r) {
  std::vector<CollisionGroup> groups;
  for (const CollisionRun& c : r.runs) {
    auto it = std::find_if(groups.begin(), groups.end(), [&](const CollisionGroup& g) {
      return g.first->region.name == c.region.name && g.first->motion == c.motion &&
             g.first->nominal_speed_m_s == c.nominal_speed_m_s && g.first->clamped == c.clamped;
    });
    if (it == groups.end()) {
      groups.emplace_back();
      groups.back().first = &c;
      it = groups.end() - 1;
    }
    CollisionGroup& g = *it;
    if (!c.valid) {
      ++g.invalid;
      continue;
    }
    const int w = c.constraint ? 1 : 0;
    g.speed[w] = std::max(g.speed[w], c.approach_speed_m_s);
    if (c.permissible_speed_m_s > 0.0) g.vmax = std::min(g.vmax, c.permissible_speed_m_s);
    g.peak[w] = std::max(g.peak[w], c.peak_force_N);
    g.clamp[w] = std::max(g.clamp[w], c.quasi_static_force_N);
    g.over[w] += over_limit(c) ? 1 : 0;
    ++g.count[w];
  }
  return groups;
}

std::string group_label(const CollisionRun& c) {
  return c.region.name + ", " + to_string(c.motion) +
         (c.motion == CollisionMotion::kPointToPoint ? " at " + format_fixed(c.nominal_speed_m_s, 2) + " m/s" : "") + ", " +
         (c.clamped ? "clamped" : "free");
}

// The conclusions, from this run's numbers.
std::string collision_conclusions(const std::vector<CollisionGroup>& groups) {
  int over[2] = {0, 0}, count[2] = {0, 0}, invalid = 0;
  double best_reduction = 0.0, worst_change = 0.0;
  const CollisionRun* best = nullptr;
  const CollisionRun* worst = nullptr;
  for (const CollisionGroup& g : groups) {
    for (int w = 0; w < 2; ++w) {
      over[w] += g.over[w];
      count[w] += g.count[w];
    }
    invalid += g.invalid;
    if (g.peak[0] <= 0.0 || g.count[1] == 0) continue;
    const double reduction = 1.0 - g.peak[1] / g.peak[0];
    if (reduction > best_reduction) {
      best_reduction = reduction;
      best = g.first;
    }
    if (-reduction > worst_change) {
      worst_change = -reduction;
      worst = g.first;
    }
  }
  std::ostringstream s;
  s << "- Without the constraint " << over[0] << " of " << count[0] << " valid collisions exceeded their region's limit "
    << "(the peak over the transient limit free, over F_QS clamped, or the clamping force over F_QS); with it " << over[1]
    << " of " << count[1] << ".\n";
  if (best) {
    s << "- The constraint lowered the worst peak force by up to " << format_fixed(100.0 * best_reduction, 0) << " % ("
      << group_label(*best) << ").\n";
  }
  if (worst) {
    s << "- It raised it by up to " << format_fixed(100.0 * worst_change, 0) << " % (" << group_label(*worst)
      << "): it bounds the speed before the touch, not the push after it.\n";
  }
  if (invalid > 0) s << "- " << invalid << " runs invalid (collision_runs.csv says why); not counted.\n";
  return s.str();
}

}  // namespace

std::string collision_table(const CollisionResult& r) {
  const CollisionOptions& o = r.options;
  std::ostringstream s;
  s << "Simulated collisions (ISO/TS 15066 power and force limiting; plant " << o.plant_config_path << ", seed " << o.seed
    << "): the tool meets a body region (mass m_H behind a spring k, regions " << o.regions_file
    << "), free (transient contact) or backed by a wall (clamping); forces are the simulator's. Peak force and, "
       "clamped, the force after "
    << format_fixed(o.contact_window_s, 1) << " s, without / with the power-and-force-limiting constraint (worst over the "
    << o.modes.size() << " compliance modes and " << o.loops.size() << " loops; valid runs only):\n\n";
  s << "| region | motion | contact | limit [N] | speed at touch [m/s] (v_max) | peak [N] unlimited | peak [N] limited | "
       "clamping force [N] unlimited / limited (F_QS) | runs over the limit unlimited / limited | invalid |\n";
  s << "|---|---|---|---|---|---|---|---|---|---|\n";
  const std::vector<CollisionGroup> groups = collision_groups(r);
  for (const CollisionGroup& g : groups) {
    const CollisionRun& c = *g.first;
    s << "| " << c.region.name << " | " << to_string(c.motion);
    if (c.motion == CollisionMotion::kPointToPoint) s << " " << format_fixed(c.nominal_speed_m_s, 2) << " m/s";
    s << " | " << (c.clamped ? "clamped" : "free") << " | " << format_fixed(c.limit_N(), 0) << " | "
      << format_fixed(g.speed[0], 2) << " / " << format_fixed(g.speed[1], 2) << " ("
      << (g.vmax < 1e9 ? format_fixed(g.vmax, 2) : std::string("-")) << ") | " << format_fixed(g.peak[0], 0) << " | "
      << format_fixed(g.peak[1], 0) << " | ";
    if (c.clamped) {
      s << format_fixed(g.clamp[0], 0) << " / " << format_fixed(g.clamp[1], 0) << " ("
        << format_fixed(c.region.quasi_static_force_N, 0) << ")";
    } else {
      s << "-";
    }
    s << " | " << g.over[0] << " of " << g.count[0] << " / " << g.over[1] << " of " << g.count[1] << " | " << g.invalid
      << " |\n";
  }
  s << "\n" << mode_loop_table(r) << "\n" << collision_conclusions(groups);
  return s.str();
}

int run_collision_command(const CollisionOptions& options, std::ostream& out) {
  collision_regions(options);  // a refusal before anything is printed
  out << "Collision test: " << options.regions.size() << " regions, " << options.speeds_m_s.size()
      << " point-to-point speeds" << (options.dynamic ? " and the dynamic scenario" : "") << ", free and clamped, "
      << options.modes.size() << " modes x " << options.loops.size() << " loops, without and with the constraint" << std::endl;
  const CollisionResult r = run_collision(options, &out);
  report_experiment({collision_table(r), r.files, options.output_dir, options.figure_script, "collision.png"}, out);
  for (const CollisionRun& c : r.runs) {
    if (!c.valid) return 1;
  }
  return 0;
}

}  // namespace phri
