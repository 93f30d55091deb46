#include <phri/experiments/safety_fuzz.hpp>

#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/fault_injecting_robot.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/capsule_fit.hpp>
#include <phri/robot/drive_kind.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>

#include <algorithm>
#include <numbers>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <sstream>
#include <thread>

namespace phri {
namespace {

constexpr double kFirstPushSettleMax_s = 2.0;  // the longest wait for a still arm before the first push

// MuJoCo's XML compiler keeps global state in some versions: plants are built one at a time.
// Everything after construction (mj_step on a plant's own mjData) runs in parallel.
std::mutex& plant_construction_mutex() {
  static std::mutex m;
  return m;
}

// What every run shares, loaded once and read only: the plant's base configuration, the
// controller's robot, the pushes toward the limits and the fault catalogue.
struct Shared {
  const SafetyFuzzOptions& o;
  ControllerSettings settings;  // the robot's (chain, frames, payloads); mode and loop set per run
  std::vector<double> start_q;
  SimRobotConfig plant;
  Model model;
  ActuatorTable actuators;
  std::optional<CollisionModel> collision;
  Eigen::VectorXd velocity_limit, torque_limit;
  std::vector<PushSpec> targeted;
  std::vector<FaultCase> faults;
  double dt = 1e-3;
  std::vector<LowLevelMode> loops;    // o.loops the drive offers: the ones run
  std::vector<LowLevelMode> skipped;  // o.loops the drive does not offer: not run, not counted
};

ControllerSettings controller_settings(const Shared& shared, ComplianceMode mode) {
  ControllerSettings s = shared.settings;
  s.initial_compliance = mode;
  s.initial_loop = LowLevelMode::kPosition;
  return s;
}

// The joint-limit pushes (each limited joint, both ways) and the wrist fold, from the start pose.
std::vector<PushSpec> targeted_pushes(const Shared& s) {
  Data data(s.model);
  Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(s.start_q.data(), static_cast<Eigen::Index>(s.start_q.size()));
  forward_kinematics(s.model, data, q);
  update_frame_placements(s.model, data);
  std::vector<PushSpec> pushes;
  for (int j = 0; j < s.model.nq(); ++j) {
    if (!s.model.joint(j).has_position_limits()) continue;
    for (int toward : {-1, 1}) {
      PushSpec p = joint_limit_push(s.model, data, j, toward, s.o.targeted_force_N, s.o.limit_push_s);
      if (p.body >= 0) pushes.push_back(p);
    }
  }
  if (s.model.has_frame("spherical_wrist_2_link")) {
    pushes.push_back(wrist_fold_push(s.model, data, "spherical_wrist_2_link", Eigen::Vector3d(0, 0, 0.1),
                                     s.o.targeted_force_N, s.o.wrist_fold_s));
  }
  return pushes;
}

// The robot under test: the Gen3's files of the options, or a robot bundle's.
struct RobotUnderTest {
  SimRobotConfig plant;
  ControllerSettings settings;
  std::string urdf_path;
  std::vector<double> start_q;
  bool fit_capsules = false;  // the bundle has no collision.yaml
};

RobotUnderTest robot_under_test(const SafetyFuzzOptions& o) {
  RobotUnderTest r;
  r.settings.initial_loop = LowLevelMode::kPosition;
  if (o.robot_folder.empty()) {
    r.plant = SimRobotConfig::from_yaml_file(o.plant_config_path);
    r.settings.urdf_path = r.urdf_path = o.urdf_path;
    r.settings.actuators_path = o.actuators_path;
    r.settings.collision_path = o.collision_path;
    r.settings.end_effector_frame = o.end_effector_frame;
    r.settings.set_end_of_arm(r.plant.end_of_arm());  // the F/T sensor and tool the plant file states
    r.settings.offered_loops = offered_loops(r.plant.drive);  // the plant's drives decide the loops
    r.start_q = o.start_q_rad;
    return r;
  }
  const RobotBundle bundle = RobotBundle::from_folder(o.robot_folder);
  r.plant.source = bundle.source;
  bundle.apply_to(r.plant);
  r.plant.fill_defaults();
  bundle.apply_to(r.settings);
  r.urdf_path = bundle.urdf_path;
  r.start_q = bundle.home_q_rad;
  r.fit_capsules = bundle.collision_path.empty() && bundle.collision_yaml.empty();
  return r;
}

std::optional<CollisionModel> robot_collision(const RobotUnderTest& r, const Model& model) {
  if (r.fit_capsules) {
    std::ifstream file(r.urdf_path);
    std::stringstream urdf;
    urdf << file.rdbuf();
    const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(r.start_q.data(), static_cast<Eigen::Index>(r.start_q.size()));
    return CollisionModel::from_yaml_string(fit_capsules(urdf.str(), model, home, {.link_frame_radius_m = 0.04, .clearance_m = 0.02}).yaml,
                                            model, "capsules fitted from " + r.urdf_path);
  }
  return Controller::collision_model(r.settings, model);
}

std::unique_ptr<Shared> load_shared(const SafetyFuzzOptions& o) {
  const std::string src = "<safety fuzz options>";
  if (o.pushes < 0 || o.pushes_per_run < 1 || o.jobs < 1) {
    throw ConfigError(src, "pushes/pushes_per_run/jobs", "need pushes >= 0, pushes_per_run >= 1, jobs >= 1");
  }
  if (o.modes.empty() || o.loops.empty()) throw ConfigError(src, "modes/loops", "nothing to run");
  if (!(o.position_phase_s >= 0.3 && o.settle_s >= 0.0)) throw ConfigError(src, "position_phase_s", "must be >= 0.3 s (F/T bias)");
  RobotUnderTest robot = robot_under_test(o);
  if (robot.start_q.size() != static_cast<std::size_t>(robot.plant.dof())) throw ConfigError(src, "start_q_rad", "needs one value per joint");
  robot.plant.initial_q_rad = robot.start_q;
  robot.plant.mismatch.enabled = o.model_mismatch;
  Model model = Model::from_urdf_file(robot.urdf_path, Controller::model_options(robot.settings));
  ActuatorTable actuators = ActuatorTable::from_yaml_file(robot.settings.actuators_path);
  std::optional<CollisionModel> collision = robot_collision(robot, model);
  if (!collision) throw ConfigError(src, "collision_path", "the pushes land on the collision capsules: a collision model is needed");
  auto s = std::unique_ptr<Shared>(new Shared{o, robot.settings, robot.start_q, std::move(robot.plant), std::move(model),
                                              std::move(actuators), std::move(collision), Eigen::VectorXd(), Eigen::VectorXd(),
                                              {}, {}, 1e-3, {}, {}});
  const int n = s->model.nv();
  s->velocity_limit.resize(n);
  s->torque_limit.resize(n);
  for (int i = 0; i < n; ++i) {
    s->velocity_limit[i] = s->actuators[i].velocity_limit_rad_s;
    s->torque_limit[i] = s->actuators[i].torque_limit_Nm;
  }
  s->dt = s->plant.control_period_s;
  s->targeted = targeted_pushes(*s);
  s->faults = fault_catalogue(o.faults, n, o.seed);
  // A loop the drive does not offer would be refused by the controller (the position loop runs in
  // its place): its rows are not run and not counted, only reported as skipped.
  for (LowLevelMode loop : o.loops) (s->settings.offered_loops.contains(loop) ? s->loops : s->skipped).push_back(loop);
  if (s->loops.empty()) throw ConfigError(src, "loops", "the drive offers none of the loops asked for");
  return s;
}

bool setpoint_finite(const RobotCommand& c) {
  switch (c.mode) {
    case LowLevelMode::kPosition: return c.q_rad.allFinite();
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
    case LowLevelMode::kTorque: return c.tau_Nm.allFinite();
    case LowLevelMode::kCurrent: return c.current_A.allFinite();
  }
  return false;
}

std::unique_ptr<SimRobot> make_plant(const Shared& s, std::uint64_t plant_seed) {
  SimRobotConfig config = s.plant;
  config.seed = plant_seed;
  const std::lock_guard<std::mutex> lock(plant_construction_mutex());
  return std::make_unique<SimRobot>(config);
}

// Between the plant and the fault injector: checks the plant's truth after every read the
// controller does not see (a stall reads the plant many times in one control cycle), so that what
// the arm does during a stall is judged too. The state the controller sees is checked by Rig::step.
class PlantTap final : public RobotInterface {
public:
  explicit PlantTap(SimRobot& plant) : plant_(plant) {}
  int dof() const override { return plant_.dof(); }
  double period_s() const override { return plant_.period_s(); }
  const RobotState& read() override {
    if (reads_ > 0 && monitor_ != nullptr && metrics_ != nullptr) {
      monitor_->update(plant_.truth().q_rad, plant_.truth().qd_rad_s, *metrics_);
      if (held_ != nullptr) held_->sample(monitor_->speed_ratio(), true, *metrics_);  // a stalled period
    }
    ++reads_;
    return plant_.read();
  }
  WriteStatus write(const RobotCommand& command) override { return plant_.write(command); }
  // Before each control cycle's read.
  void begin_cycle(SafetyMonitor* monitor, WindowMetrics* m, HeldCommandTracker* held) {
    monitor_ = monitor;
    metrics_ = m;
    held_ = held;
    reads_ = 0;
  }
  // The cycle's read ran the plant more than one period: the controller's thread stalled.
  bool stalled() const { return reads_ > 1; }

private:
  SimRobot& plant_;
  SafetyMonitor* monitor_ = nullptr;
  WindowMetrics* metrics_ = nullptr;
  HeldCommandTracker* held_ = nullptr;
  long reads_ = 0;
};

// One plant, its fault injector and one controller, driven read -> step -> write as
// app/run_session.cpp does, with the checks of SafetyMonitor on the plant's truth every cycle.
class Rig {
public:
  Rig(const Shared& s, ComplianceMode mode, LowLevelMode loop, std::uint64_t plant_seed, const FaultSpec& fault)
      : s_(s),
        mode_(mode),
        loop_(loop),
        robot_(make_plant(s, plant_seed)),
        tap_(*robot_),
        io_(tap_, fault),
        cycle_(s.model, s.actuators, s.collision, controller_settings(s, mode)),
        command_(robot_->dof()),
        targets_(robot_->dof()),
        monitor_(s.model, &*s.collision, s.velocity_limit, s.torque_limit) {}

  // One control cycle; the checks go into m.
  void step(WindowMetrics& m) {
    tap_.begin_cycle(&monitor_, &m, &held_);
    const RobotState& state = io_.read();
    // The period this read ran: on a command the controller could not renew (the last of a
    // stall's, or after a refused write), or one of the two after such a period (the renewed
    // command is written at the end of the first; the drive's torque follows it within the next).
    const bool held_period = tap_.stalled() || write_refused_;
    const bool held = held_period || periods_since_held_ < kRenewedCommandPeriods;
    periods_since_held_ = held_period ? 0 : periods_since_held_ + 1;
    if (state.fault) m.crashed = true;
    const CycleStatus status = cycle_.step(state, targets_, command_);
    targets_.clear();
    if (refusal_pending_ && status != CycleStatus::kSafeStop) ++m.unhandled_refusals;
    refusal_pending_ = false;
    if (!setpoint_finite(command_)) m.nan_command = true;
    check_intent(m);
    if (trace_.is_open()) write_trace_row(status);
    write_refused_ = false;
    if (io_.write(command_) != WriteStatus::kOk) {
      const bool injected = io_.fault_active() && io_.fault().kind == FaultKind::kWriteRefused;
      if (!injected) ++m.refused_writes;
      refusal_pending_ = true;
      // Answered in the same cycle (controller.hpp); a second refusal counts as well.
      write_refused_ = true;
      if (cycle_.answer_refused_write(state, command_)) {
        write_refused_ = io_.write(command_) != WriteStatus::kOk;
        if (write_refused_ && !injected) ++m.refused_writes;
      }
    }
    const SimRobot::Truth& truth = robot_->truth();
    monitor_.update(truth.q_rad, truth.qd_rad_s, m);
    held_.sample(monitor_.speed_ratio(), held, m);
    speed_ = truth.qd_rad_s.cwiseAbs().maxCoeff();
  }

  // Position loop for position_phase_s, the switch to the loop under test, settle_s. The checks
  // into m (recovery does not apply); false when the start-up already violated something or stopped.
  // With stay_in_position the run stays in the position loop (a loop switch comes later:
  // request_loop()).
  bool warm_up(WindowMetrics& m, bool stay_in_position = false) {
    const long n1 = std::lround(s_.o.position_phase_s / s_.dt), n2 = std::lround(s_.o.settle_s / s_.dt);
    for (long k = 0; k < n1 + n2; ++k) {
      if (k == n1 && !stay_in_position) request_loop(loop_);
      step(m);
    }
    m.recovery_time_s = 0.0;
    m.safe_stop = cycle_.supervisor().safe_stop();
    m.safe_stop_rest_time_s = m.safe_stop ? -1.0 : 0.0;
    return classify(m, s_.o.thresholds).violations == 0 && !m.safe_stop;
  }

  // Before the first push: on until the arm is still (as between pushes), for at most max_s, so
  // that the held pose the pushes are judged against is not a pose the arm was passing through.
  // No cycle at all when it already is (the usual case). The checks go into m, as in warm_up(),
  // and the same verdict comes back.
  bool settle(WindowMetrics& m, double max_s) {
    const long n = std::lround(max_s / s_.dt);
    for (long k = 0; k < n && speed_ >= s_.o.thresholds.settle_speed_rad_s; ++k) step(m);
    m.safe_stop = cycle_.supervisor().safe_stop();
    m.safe_stop_rest_time_s = m.safe_stop ? -1.0 : 0.0;
    return classify(m, s_.o.thresholds).violations == 0 && !m.safe_stop;
  }

  // Every later cycle as one CSV row (a replay's --trace); appends when `append`.
  void trace_to(const std::string& path, bool append) {
    trace_.open(path, append ? std::ios::app : std::ios::trunc);
    if (!trace_) throw ConfigError(path, "trace", "cannot write the trace file");
    if (append) return;
    trace_ << "t_s,status,safety_state";
    const int n = robot_->dof();
    for (const char* name : {"q", "qd", "command", "tau_ext_hat", "tau_sensor_true", "tau_friction", "posture_integral",
                             "qdd_desired", "tau_desired"}) {
      for (int i = 0; i < n; ++i) trace_ << ',' << name << i + 1;
    }
    for (int i = 0; i < n; ++i) trace_ << ",leash_offset" << i + 1;
    for (const char* name : {"ee_error", "ee_integral"}) {
      for (int i = 0; i < 6; ++i) trace_ << ',' << name << i + 1;
    }
    trace_ << ",qp_status,min_capsule_distance_m";
    trace_ << '\n';
  }

  double time() const { return robot_->state().time_s; }
  long cycles() const { return io_.cycles(); }  ///< control cycles (reads the controller saw)
  long plant_cycles() const { return static_cast<long>(robot_->state().cycle); }  ///< periods the plant ran
  LowLevelMode running_loop() const { return cycle_.low_level().loop(); }
  void request_loop(LowLevelMode loop) {  ///< at the next step
    targets_.low_level_mode = loop;
    expected_loop_ = loop;
  }
  const FaultInjectingRobot& injector() const { return io_; }
  double speed() const { return speed_; }
  double safe_stop_time() const {
    return cycle_.supervisor().safe_stop() ? cycle_.supervisor().safe_stop_transition().time_s : -1.0;
  }
  std::string safe_stop_reason() const {
    if (!cycle_.supervisor().safe_stop()) return {};
    const SafetyTransition& tr = cycle_.supervisor().safe_stop_transition();
    std::string r(to_string(tr.reason));
    if (tr.joint >= 0) r += " (joint " + std::to_string(tr.joint + 1) + ")";
    return r;
  }
  const Eigen::VectorXd& q() const { return robot_->truth().q_rad; }
  SimRobot& robot() { return *robot_; }
  SafetyMonitor& monitor() { return monitor_; }

private:
  void write_trace_row(CycleStatus status) {
    const SimRobot::Truth& truth = robot_->truth();
    const Eigen::VectorXd& cmd = command_.mode == LowLevelMode::kPosition ? command_.q_rad
                                 : command_.mode == LowLevelMode::kCurrent ? command_.current_A
                                                                           : command_.tau_Nm;
    trace_ << robot_->state().time_s << ',' << to_string(status) << ',' << to_string(cycle_.supervisor().state());
    for (const Eigen::VectorXd* v : {&truth.q_rad, &truth.qd_rad_s, &cmd, &cycle_.external_torque(),
                                     &truth.tau_transmitted_Nm, &truth.tau_friction_Nm,
                                     &cycle_.qp().posture().integral_term(),
                                     &cycle_.qp().desired_acceleration(), &cycle_.qp().desired_torque(),
                                     &cycle_.leash().offset()}) {
      for (Eigen::Index i = 0; i < v->size(); ++i) trace_ << ',' << (*v)[i];
    }
    for (const Vector6d* v : {&cycle_.qp().end_effector().error(), &cycle_.qp().end_effector().integral_term()}) {
      for (Eigen::Index i = 0; i < 6; ++i) trace_ << ',' << (*v)[i];
    }
    const CollisionData* collision = cycle_.qp().collision_data();
    trace_ << ',' << to_string(cycle_.qp().status()) << ','
           << (collision != nullptr && collision->distance.size() > 0 ? collision->distance.minCoeff()
                                                                       : std::numeric_limits<double>::infinity());
    trace_ << '\n';
  }

  // Whether the loop and mode under test are the ones running (before a safe stop, which holds in
  // the position loop by design); what ran instead is kept for the report.
  void check_intent(WindowMetrics& m) const {
    if (cycle_.supervisor().safe_stop()) return;
    const LowLevelMode ran = cycle_.low_level().loop();
    if (ran == expected_loop_ && cycle_.compliance().mode() == mode_) return;
    if (m.off_intent_cycles++ == 0) {
      m.ran_loop = static_cast<int>(ran);
      m.ran_mode = static_cast<int>(cycle_.compliance().mode());
    }
  }

  const Shared& s_;
  ComplianceMode mode_;
  LowLevelMode loop_;
  LowLevelMode expected_loop_ = LowLevelMode::kPosition;  // the run starts in the position loop
  std::unique_ptr<SimRobot> robot_;
  PlantTap tap_;
  FaultInjectingRobot io_;
  Controller cycle_;
  RobotCommand command_;
  ControllerTargets targets_;
  SafetyMonitor monitor_;
  std::ofstream trace_;
  bool refusal_pending_ = false;
  HeldCommandTracker held_{s_.o.thresholds.speed_factor};
  bool write_refused_ = false;  // this cycle's command did not reach the robot
  static constexpr long kRenewedCommandPeriods = 2;
  long periods_since_held_ = kRenewedCommandPeriods;  // since a period ran on a command not renewed
  double speed_ = 0.0;
};

// What a task hands back: its records, and what it cost.
struct TaskOutput {
  std::vector<FuzzRecord> records;
  int rigs = 0;
  double simulated_s = 0.0;
};

FuzzRecord base_record(const std::string& run_id, int index, FuzzCaseKind kind, ComplianceMode mode, LowLevelMode loop,
                       std::uint64_t plant_seed) {
  FuzzRecord r;
  r.run_id = run_id;
  r.index = index;
  r.kind = kind;
  r.mode = mode;
  r.loop = loop;
  r.plant_seed = plant_seed;
  return r;
}

void describe_push(FuzzRecord& r, const PushSpec& p) {
  r.kind = p.kind == PushKind::kRandom ? FuzzCaseKind::kRandomPush
           : p.kind == PushKind::kJointLimit ? FuzzCaseKind::kLimitPush
                                              : FuzzCaseKind::kWristFold;
  r.target = p.link;
  r.joint = p.joint;
  r.force_N = p.magnitude_N;
  r.profile = std::string(to_string(p.profile));
  r.duration_s = p.duration_s;
}

// One push on a warmed-up rig, until the arm is back and settled, or stopped, or out of time.
// The reference is q_ref (the held pose). In dual compliance a hand on the end effector sets a new
// pose, so there "back" means back at q_ref (an untouched end effector keeps its target, and the
// posture walks home like in null-space compliance) or at rest wherever the hand left it.
// Returns whether the rig can take the next push.
bool run_push(Rig& rig, const Shared& s, const PushSpec& p, const Eigen::VectorXd& q_ref, bool dual, FuzzRecord& r) {
  const SafetyFuzzThresholds& th = s.o.thresholds;
  WindowMetrics& m = r.metrics;
  const double start = rig.time();
  r.start_s = start;
  const ExternalForce force = p.disturbance(start);
  const int plant_body = rig.robot().body_id(p.plant_link());
  if (plant_body < 0) throw ConfigError(s.o.plant_config_path, "bodies", "the plant has no body '" + p.plant_link() + "' to push");
  rig.robot().set_live_disturbance(plant_body, force);
  RecoveryTracker tracker(th, start + p.duration_s, s.o.min_pause_s);
  // Room for the longest walk back (half a turn beyond any joint's range is not possible: 2 pi).
  const double walk_back_s = 2.0 * std::numbers::pi / th.return_speed_rad_s;
  const long max_cycles =
      std::lround((p.duration_s + th.recovery_time_s + walk_back_s + th.safe_stop_rest_time_s + 0.5) / s.dt);
  for (long k = 0; k < max_cycles && !tracker.done() && !m.crashed; ++k) {
    rig.step(m);
    const double t = rig.time();
    // The plant applied the force over the period that ended at t: its value mid-period.
    const double scale = force.scale_at(t - 0.5 * s.dt);
    if (scale > 0.0) rig.monitor().push_torque_ratio(p.body, p.point_local, scale * p.force_N, p.local_frame, m);
    int joint = -1;
    const double from_reference = rig.monitor().deviation(rig.q(), q_ref, joint);
    const bool rests_where_left = dual && rig.speed() < th.rest_speed_rad_s;
    const double deviation = rests_where_left ? 0.0 : from_reference;
    m.final_deviation_rad = deviation;
    m.final_deviation_joint = rests_where_left ? -1 : joint;  // no joint is "off" when the arm may rest there
    if (t >= start + p.duration_s) m.max_deviation_rad = std::max(m.max_deviation_rad, deviation);
    m.final_speed_rad_s = rig.speed();
    tracker.sample(t, deviation, rig.speed(), rig.safe_stop_time());
  }
  rig.robot().set_live_disturbance(-1, force);
  tracker.finish(m);
  r.verdict = classify(m, th);
  r.safe_stop_reason = rig.safe_stop_reason();
  if (m.crashed) r.error = "the simulated plant diverged";
  return !m.safe_stop && !m.crashed && m.recovery_time_s >= 0.0;
}

std::uint64_t plant_seed_of(std::uint64_t base, int rebuild) { return mix_seed(base, static_cast<std::uint64_t>(rebuild)) >> 2; }

// A run of pushes on one pair: a plant and a controller, warmed up, take the pushes one after the
// other; after a safe stop, a window without recovery or a crash, a fresh pair goes on.
void push_run(const Shared& s, const std::string& id, ComplianceMode mode, LowLevelMode loop,
              const std::vector<PushSpec>& pushes, std::uint64_t base_seed, TaskOutput& out) {
  std::size_t next = 0;
  for (int rebuild = 0; next < pushes.size(); ++rebuild) {
    const std::uint64_t seed = plant_seed_of(base_seed, rebuild);
    FuzzRecord r = base_record(id, static_cast<int>(next), FuzzCaseKind::kStartup, mode, loop, seed);
    try {
      Rig rig(s, mode, loop, seed, FaultSpec{});
      ++out.rigs;
      if (!s.o.trace_path.empty()) rig.trace_to(s.o.trace_path, rebuild > 0);
      if (!rig.warm_up(r.metrics) || !rig.settle(r.metrics, kFirstPushSettleMax_s)) {
        r.verdict = classify(r.metrics, s.o.thresholds);
        r.safe_stop_reason = rig.safe_stop_reason();
        out.records.push_back(r);
        out.simulated_s += rig.time();
        return;  // the pushes left cannot be tested on this pair
      }
      const Eigen::VectorXd q_ref = rig.q();
      bool usable = true;
      while (usable && next < pushes.size()) {
        FuzzRecord push = base_record(id, static_cast<int>(next), FuzzCaseKind::kRandomPush, mode, loop, seed);
        describe_push(push, pushes[next]);
        usable = run_push(rig, s, pushes[next], q_ref, mode == ComplianceMode::kDual, push);
        out.records.push_back(push);
        ++next;
      }
      out.simulated_s += rig.time();
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      describe_push(r, pushes[next]);
      r.metrics.crashed = true;
      r.error = e.what();
      r.verdict = classify(r.metrics, s.o.thresholds);
      out.records.push_back(r);
      ++next;
    }
  }
}

// The fault-free path of a (mode, loop): the plant's true q after every read().
struct ReferencePath {
  Eigen::MatrixXd q;  // nq x cycles
  bool ready = false;
};

long fault_window_cycles(const Shared& s, long fault_cycles) {
  const SafetyFuzzThresholds& th = s.o.thresholds;
  return fault_cycles + std::lround((th.recovery_time_s + th.safe_stop_rest_time_s + 0.2) / s.dt);
}

long warm_up_cycles(const Shared& s) { return std::lround(s.o.position_phase_s / s.dt) + std::lround(s.o.settle_s / s.dt); }

std::uint64_t fault_seed(const Shared& s, ComplianceMode mode, LowLevelMode loop) {
  return mix_seed(mix_seed(s.o.seed, 0xFA17), static_cast<std::uint64_t>(static_cast<int>(mode) * 8 + static_cast<int>(loop))) >> 2;
}

// Extra plant periods a fault takes in one control cycle (a stall's), 0 for the others.
long stall_periods(const FaultSpec& f) { return f.kind == FaultKind::kStall ? std::lround(std::max(0.0, f.value)) : 0; }

// The lengths a fault runs at rest: its own, or each of the options'.
std::vector<long> rest_cycles(const Shared& s, const FaultCase& f) {
  return f.fixed_cycles > 0 ? std::vector<long>{f.fixed_cycles} : s.o.fault_cycles;
}

// The longest window at rest in plant periods (a stall's periods count).
long longest_rest_fault(const Shared& s) {
  long longest = 0;
  for (const FaultCase& f : s.faults) {
    for (long c : rest_cycles(s, f)) longest = std::max(longest, c + stall_periods(f.spec));
  }
  for (long c : s.o.fault_cycles) longest = std::max(longest, c);
  return longest;
}

// Which record fields say what a fault is.
void describe_fault(FuzzRecord& r, const FaultCase& fault, long cycles) {
  r.target = fault.name;
  const bool per_joint = fault.spec.signal != FaultSignal::kWrench &&
                         (fault.spec.kind == FaultKind::kNaN || fault.spec.kind == FaultKind::kInf ||
                          fault.spec.kind == FaultKind::kAdd || fault.spec.kind == FaultKind::kDrift);
  r.joint = per_joint ? fault.spec.joint : -1;
  r.fault_cycles = cycles;
  r.fault_kind = std::string(to_string(fault.spec.kind));
}

// A run that threw (not a configuration error): a crash, with the exception's message.
void record_crash(FuzzRecord& r, const std::exception& e) {
  r.metrics.crashed = true;
  r.error = e.what();
}

void finish_record(const Shared& s, FuzzRecord& r, TaskOutput& out) {
  r.verdict = classify(r.metrics, s.o.thresholds);
  out.records.push_back(r);
}

// The fault-free run of a (mode, loop) with the faulted runs' plant seed: its path, and its own
// checks (a record of kind kReference).
void reference_run(const Shared& s, const std::string& id, ComplianceMode mode, LowLevelMode loop, ReferencePath& path,
                   TaskOutput& out) {
  const std::uint64_t seed = fault_seed(s, mode, loop);
  FuzzRecord r = base_record(id, 0, FuzzCaseKind::kReference, mode, loop, seed);
  r.target = "none";
  r.context = "rest";
  const long total = warm_up_cycles(s) + fault_window_cycles(s, longest_rest_fault(s));
  try {
    Rig rig(s, mode, loop, seed, FaultSpec{});
    ++out.rigs;
    path.q = Eigen::MatrixXd::Zero(s.model.nq(), total);
    rig.warm_up(r.metrics);
    r.start_s = rig.time();
    while (rig.plant_cycles() < total && !r.metrics.crashed) {
      rig.step(r.metrics);
      path.q.col(rig.plant_cycles() - 1) = rig.q();
    }
    r.metrics.recovery_time_s = 0.0;
    r.metrics.safe_stop = rig.safe_stop_time() >= 0.0;
    r.metrics.safe_stop_time_s = rig.safe_stop_time();
    r.safe_stop_reason = rig.safe_stop_reason();
    out.simulated_s += rig.time();
    path.ready = true;
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    record_crash(r, e);
  }
  finish_record(s, r, out);
}

// One fault case for `fault_cycles` cycles right after the warm-up, compared with the reference path.
void fault_run(const Shared& s, const std::string& id, ComplianceMode mode, LowLevelMode loop, const FaultCase& fault,
               long fault_cycles, const ReferencePath& path, TaskOutput& out) {
  const std::uint64_t seed = fault_seed(s, mode, loop);
  FuzzRecord r = base_record(id, 0, FuzzCaseKind::kFault, mode, loop, seed);
  describe_fault(r, fault, fault_cycles);
  r.context = "rest";
  FaultSpec spec = fault.spec;
  spec.start_cycle = warm_up_cycles(s);
  spec.cycles = fault_cycles;
  try {
    Rig rig(s, mode, loop, seed, spec);
    ++out.rigs;
    if (!s.o.trace_path.empty()) rig.trace_to(s.o.trace_path, false);
    WindowMetrics warm;
    rig.warm_up(warm);  // identical to the reference's start-up (its record judges it)
    WindowMetrics& m = r.metrics;
    r.start_s = rig.time();
    // The window's end in plant time: a stall's periods run inside its one control cycle. The path
    // is indexed by the plant's cycle (after a stall the controller's cycles lag the plant's).
    const long periods = fault_cycles + stall_periods(spec);
    RecoveryTracker tracker(s.o.thresholds, rig.time() + static_cast<double>(periods) * s.dt, s.o.fault_observation_s);
    const long end = std::min<long>(path.q.cols(), spec.start_cycle + fault_window_cycles(s, periods));
    while (rig.plant_cycles() < end && !tracker.done() && !m.crashed) {
      rig.step(m);
      int joint = -1;
      const double deviation = rig.monitor().deviation(rig.q(), path.q.col(rig.plant_cycles() - 1), joint);
      m.max_deviation_rad = std::max(m.max_deviation_rad, deviation);
      m.final_deviation_rad = deviation;
      m.final_deviation_joint = joint;
      m.final_speed_rad_s = rig.speed();
      tracker.sample(rig.time(), deviation, rig.speed(), rig.safe_stop_time());
    }
    tracker.finish(m);
    r.safe_stop_reason = rig.safe_stop_reason();
    if (m.crashed) r.error = "the simulated plant diverged";
    out.simulated_s += rig.time();
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    record_crash(r, e);
  }
  finish_record(s, r, out);
}

// ---- faults in motion and after a loop switch (safety_fuzz.hpp, 2b)

// One (context, mode, loop): its push, its loop switch, its plant seed and the fault-free path.
struct MotionScenario {
  bool with_switch = false;  // "switch": position loop until switch_offset cycles into the push
  ComplianceMode mode = ComplianceMode::kStiff;
  LowLevelMode loop = LowLevelMode::kPosition;
  std::uint64_t key = 0;     // seeds of the faults' start times
  std::uint64_t plant_seed = 0;
  PushSpec push;
  long switch_offset = 0;    // cycles after the push began
  // Filled by the reference run: the plant's true q after each read (column = plant cycle - 1),
  // from the push on, the control cycle the push began at and the one the switch took effect in.
  Eigen::MatrixXd q;
  long push_cycle = -1;
  long switched_cycle = -1;
  bool ready = false;

  const char* context() const { return with_switch ? "switch" : "motion"; }
};

// Cycles a fault starts after the push began (motion) or after the loop switch (switch), drawn
// from the seed, the pair and the fault's name (not its place in the catalogue).
long motion_fault_offset(const Shared& s, const MotionScenario& sc, const FaultCase& fault) {
  RandomGenerator rng(mix_seed(sc.key, name_hash(fault.name)), 3);
  const MotionFaultRanges& r = s.o.motion;
  const double offset_s = sc.with_switch ? rng.uniform(0.0, r.max_switch_delay_s) : rng.uniform(r.min_fault_start_s, r.max_fault_start_s);
  return std::lround(offset_s / s.dt);
}

// Plant cycles a motion reference runs at least after its push began: past the latest fault start,
// the longest fault, the push, the recovery time and the safe stop's rest time (and 2 s more).
long motion_horizon_cycles(const Shared& s, const MotionScenario& sc) {
  const SafetyFuzzThresholds& th = s.o.thresholds;
  long longest = 0;
  for (const FaultCase& f : s.faults) longest = std::max(longest, f.cycles_in_motion() + stall_periods(f.spec));
  const double latest_fault_s = static_cast<double>(sc.switch_offset) * s.dt +
                                (sc.with_switch ? s.o.motion.max_switch_delay_s : s.o.motion.max_fault_start_s);
  const double after_s = std::max(sc.push.duration_s - latest_fault_s, static_cast<double>(longest) * s.dt);
  return std::lround((latest_fault_s + after_s + th.recovery_time_s + th.safe_stop_rest_time_s + 2.0) / s.dt);
}

// One run of a motion scenario: the reference (fault null) records the path and is judged as a
// push (back at the pose held before it, dual compliance: or at rest); a faulted run is judged from
// its fault on against the reference's path.
// The record of a motion window and, for a faulted one, its fault placed in the push.
FuzzRecord motion_record(const Shared& s, const std::string& id, const MotionScenario& sc, const FaultCase* fault,
                         FaultSpec& spec, long& fault_cycles) {
  const bool reference = fault == nullptr;
  FuzzRecord r = base_record(id, 0, reference ? FuzzCaseKind::kReference : FuzzCaseKind::kFault, sc.mode, sc.loop, sc.plant_seed);
  r.context = sc.context();
  r.push_link = sc.push.plant_link();
  r.force_N = sc.push.magnitude_N;
  r.profile = std::string(to_string(sc.push.profile));
  r.duration_s = sc.push.duration_s;
  fault_cycles = 0;
  if (reference) {
    r.target = "none";
    return r;
  }
  if (!sc.ready) throw ExperimentError("safety fuzz", "no reference path for " + id);
  fault_cycles = fault->cycles_in_motion();
  const long offset = motion_fault_offset(s, sc, *fault);
  describe_fault(r, *fault, fault_cycles);
  r.fault_offset_s = static_cast<double>(offset) * s.dt;
  spec = fault->spec;
  // After a switch: from the sample after the one the reference switched on (a bad sample with the
  // request keeps the position loop, and the window would not test the loop it names). A reference
  // that never switched leaves the request's cycle: its windows are invalid, and reported so.
  const long after_switch = sc.switched_cycle >= 0 ? sc.switched_cycle + 1 : sc.push_cycle + sc.switch_offset;
  spec.start_cycle = (sc.with_switch ? after_switch : sc.push_cycle) + offset;
  spec.cycles = fault_cycles;
  return r;
}

// The scenario's push on the rig's plant, from now.
ExternalForce start_motion_push(Rig& rig, const Shared& s, const MotionScenario& sc) {
  const ExternalForce force = sc.push.disturbance(rig.time());
  const int plant_body = rig.robot().body_id(sc.push.plant_link());
  if (plant_body < 0) {
    throw ConfigError(s.o.plant_config_path, "bodies", "the plant has no body '" + sc.push.plant_link() + "' to push");
  }
  rig.robot().set_live_disturbance(plant_body, force);
  return force;
}

// One judged cycle of a motion window: the deviation from the reference (a reference run: from the
// pose held before the push) into m and the recovery tracker.
void judge_motion_cycle(Rig& rig, const Shared& s, const MotionScenario& sc, bool reference, const Eigen::VectorXd& q_held,
                        double push_end, WindowMetrics& m, RecoveryTracker& tracker) {
  const SafetyFuzzThresholds& th = s.o.thresholds;
  const double t = rig.time();
  int joint = -1;
  const double from_reference = rig.monitor().deviation(
      rig.q(), reference ? Eigen::Ref<const Eigen::VectorXd>(q_held)
                         : Eigen::Ref<const Eigen::VectorXd>(sc.q.col(std::min<long>(rig.plant_cycles(), sc.q.cols()) - 1)),
      joint);
  // Dual compliance keeps the pose the hand left it in: at rest after the push, it is back.
  const bool rests_where_left = sc.mode == ComplianceMode::kDual && t >= push_end && rig.speed() < th.rest_speed_rad_s;
  const double deviation = rests_where_left ? 0.0 : from_reference;
  if (!reference || t >= push_end) m.max_deviation_rad = std::max(m.max_deviation_rad, deviation);
  double recovery_deviation = deviation;
  if (!reference && sc.mode != ComplianceMode::kDual && t >= push_end) {
    int rest_joint = -1;
    const double from_rest = rig.monitor().deviation(rig.q(), sc.q.col(sc.q.cols() - 1), rest_joint);
    tracker.allow_walk_back(t, from_rest);
    // A carried arm that walks back faster than the reference is back once it is where the
    // reference comes to rest, though the reference's path has not got there yet.
    if (from_rest < recovery_deviation) {
      recovery_deviation = from_rest;
      joint = rest_joint;
    }
  }
  m.final_deviation_rad = recovery_deviation;
  m.final_deviation_joint = rests_where_left ? -1 : joint;
  m.final_speed_rad_s = rig.speed();
  tracker.sample(t, recovery_deviation, rig.speed(), rig.safe_stop_time());
}

// The reference run's cycle (`cycle`: the control cycle before it): the plant's true q into the
// path, and the cycle the loop switch requested at `switch_cycle` (-1: none) took effect in.
void record_reference_cycle(const Rig& rig, MotionScenario& sc, long cycle, long switch_cycle) {
  if (switch_cycle >= 0 && sc.switched_cycle < 0 && cycle >= switch_cycle && rig.running_loop() == sc.loop) {
    sc.switched_cycle = cycle;
  }
  if (rig.plant_cycles() > sc.q.cols()) sc.q.conservativeResize(Eigen::NoChange, sc.q.cols() + 1000);
  sc.q.col(rig.plant_cycles() - 1) = rig.q();
}

// The reference run's path, cut to the plant cycles it ran, is ready for the faulted runs.
void keep_reference_path(MotionScenario& sc, long plant_cycles) {
  sc.q.conservativeResize(Eigen::NoChange, std::min<long>(sc.q.cols(), plant_cycles));
  sc.ready = true;
}

void motion_run(const Shared& s, const std::string& id, MotionScenario& sc, const FaultCase* fault, TaskOutput& out) {
  const SafetyFuzzThresholds& th = s.o.thresholds;
  const bool reference = fault == nullptr;
  FaultSpec spec;
  long fault_cycles = 0;
  FuzzRecord r = motion_record(s, id, sc, fault, spec, fault_cycles);
  WindowMetrics& m = r.metrics;
  try {
    Rig rig(s, sc.mode, sc.loop, sc.plant_seed, spec);
    ++out.rigs;
    if (!s.o.trace_path.empty()) rig.trace_to(s.o.trace_path, false);
    WindowMetrics warm;
    WindowMetrics& start_metrics = reference ? m : warm;  // a faulted run's start-up is the reference's
    rig.warm_up(start_metrics, sc.with_switch);
    rig.settle(start_metrics, kFirstPushSettleMax_s);
    const long push_cycle = rig.cycles();
    // The reference runs at least the horizon, and on until its own window is decided (a carried arm
    // walks back at the return leash's speed); the path grows as it goes. A faulted window may run as
    // long (its deviation after the reference's end is taken from the reference's last pose).
    const long horizon_end = push_cycle + motion_horizon_cycles(s, sc);
    const long cap = horizon_end + std::lround(2.0 * std::numbers::pi / th.return_speed_rad_s / s.dt);
    if (reference) {
      sc.push_cycle = push_cycle;
      sc.q = Eigen::MatrixXd::Zero(s.model.nq(), horizon_end);
    } else if (push_cycle != sc.push_cycle) {
      throw ExperimentError("safety fuzz", id + ": the run left its reference's path before the fault (push at cycle " +
                                               std::to_string(push_cycle) + ", reference " + std::to_string(sc.push_cycle) + ")");
    }
    const Eigen::VectorXd q_held = rig.q();
    const double push_start = rig.time();
    const ExternalForce force = start_motion_push(rig, s, sc);
    const double push_end = push_start + sc.push.duration_s;
    // The window's end in plant time: the push's, or the fault's when later (the fault-free run gets
    // its time after the push, so does a fault that ended while the hand still pushed).
    const long fault_end_cycle = reference ? 0 : spec.start_cycle - push_cycle + fault_cycles + stall_periods(spec);
    const double window_end = std::max(push_end, push_start + static_cast<double>(fault_end_cycle) * s.dt);
    RecoveryTracker tracker(th, window_end, reference ? s.o.min_pause_s : s.o.fault_observation_s);
    const long switch_cycle = sc.with_switch ? push_cycle + sc.switch_offset : -1;
    bool fault_seen = false;
    auto go_on = [&]() {
      if (m.crashed || rig.plant_cycles() >= cap) return false;
      return reference ? rig.plant_cycles() < horizon_end || !tracker.done() : !tracker.done();
    };
    while (go_on()) {
      if (rig.cycles() == switch_cycle) rig.request_loop(sc.loop);
      // A faulted run is the reference until its fault: judged from the fault's first cycle on.
      const bool judged = reference || rig.cycles() >= spec.start_cycle;
      WindowMetrics& cycle_metrics = judged ? m : warm;
      const long cycle = rig.cycles();
      rig.step(cycle_metrics);
      const double t = rig.time();
      if (reference) record_reference_cycle(rig, sc, cycle, switch_cycle);
      const double scale = force.scale_at(t - 0.5 * s.dt);
      if (scale > 0.0) {
        rig.monitor().push_torque_ratio(sc.push.body, sc.push.point_local, scale * sc.push.force_N, sc.push.local_frame,
                                        cycle_metrics);
      }
      if (!judged) continue;
      if (!reference && !fault_seen) {
        fault_seen = true;
        r.start_s = t;
      }
      judge_motion_cycle(rig, s, sc, reference, q_held, push_end, m, tracker);
    }
    rig.robot().set_live_disturbance(-1, force);
    if (reference) r.start_s = push_start;
    tracker.finish(m);
    r.safe_stop_reason = rig.safe_stop_reason();
    if (m.crashed) r.error = "the simulated plant diverged";
    out.simulated_s += rig.time();
    if (reference) keep_reference_path(sc, rig.plant_cycles());
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    record_crash(r, e);
  }
  finish_record(s, r, out);
}

// ---- the task list: one task per run, each a deterministic function of the options

struct FuzzTask {
  std::string id;
  double cost = 1.0;  // simulated seconds, roughly: the longest go first
  std::function<void(TaskOutput&)> run;
};

std::string pair_id(ComplianceMode mode, LowLevelMode loop) {
  return std::string(to_string(mode)) + "/" + std::string(to_string(loop));
}

std::uint64_t pair_key(ComplianceMode mode, LowLevelMode loop) {
  return static_cast<std::uint64_t>(static_cast<int>(mode) * 8 + static_cast<int>(loop));
}

// The random pushes of every pair, pushes_per_run per run.
void add_push_tasks(const Shared& s, std::vector<FuzzTask>& tasks) {
  const SafetyFuzzOptions& o = s.o;
  const int pairs = static_cast<int>(o.modes.size() * s.loops.size());
  int pair = 0;
  for (ComplianceMode mode : o.modes) {
    for (LowLevelMode loop : s.loops) {
      const int count = o.pushes / pairs + (pair < o.pushes % pairs ? 1 : 0);
      ++pair;
      const std::uint64_t key = mix_seed(o.seed, pair_key(mode, loop));
      for (int first = 0, run = 0; first < count; first += o.pushes_per_run, ++run) {
        std::vector<PushSpec> pushes;
        for (int i = first; i < std::min(count, first + o.pushes_per_run); ++i) {
          RandomGenerator rng(mix_seed(key, static_cast<std::uint64_t>(i)), 1);
          pushes.push_back(draw_random_push(rng, s.model, *s.collision, o.push_ranges));
        }
        const std::string id = "push/" + pair_id(mode, loop) + "/" + std::to_string(run);
        const std::uint64_t base = mix_seed(key, 0x5EED0000ULL + static_cast<std::uint64_t>(run));
        double cost = 1.0;
        for (const PushSpec& p : pushes) cost += p.duration_s + 0.6;
        tasks.push_back({id, cost, [&s, id, mode, loop, pushes, base](TaskOutput& out) {
                           push_run(s, id, mode, loop, pushes, base, out);
                         }});
      }
    }
  }
}

void add_targeted_tasks(const Shared& s, std::vector<FuzzTask>& tasks) {
  if (!s.o.targeted_pushes || s.targeted.empty()) return;
  for (ComplianceMode mode : s.o.modes) {
    for (LowLevelMode loop : s.loops) {
      const std::string id = "targeted/" + pair_id(mode, loop);
      const std::uint64_t base = mix_seed(mix_seed(s.o.seed, pair_key(mode, loop)), 0x7A46E7ULL);
      double cost = 1.0;
      for (const PushSpec& p : s.targeted) cost += p.duration_s + 1.0;
      tasks.push_back({id, cost, [&s, id, mode, loop, base](TaskOutput& out) {
                         push_run(s, id, mode, loop, s.targeted, base, out);
                       }});
    }
  }
}

// References first (their own phase), then one task per fault case and duration.
void add_fault_tasks(const Shared& s, std::vector<FuzzTask>& references, std::vector<FuzzTask>& tasks,
                     std::vector<std::unique_ptr<ReferencePath>>& paths) {
  if (s.faults.empty()) return;
  for (ComplianceMode mode : s.o.fault_modes) {
    for (LowLevelMode loop : s.loops) {
      paths.push_back(std::make_unique<ReferencePath>());
      ReferencePath* path = paths.back().get();
      const std::string ref_id = "reference/" + pair_id(mode, loop);
      references.push_back({ref_id, 4.0, [&s, ref_id, mode, loop, path](TaskOutput& out) {
                              reference_run(s, ref_id, mode, loop, *path, out);
                            }});
      for (const FaultCase& fault : s.faults) {
        for (long cycles : rest_cycles(s, fault)) {
          const std::string id = "fault/" + pair_id(mode, loop) + "/" + fault.name + "/" + std::to_string(cycles);
          tasks.push_back({id, 2.0, [&s, id, mode, loop, &fault, cycles, path, ref_id](TaskOutput& out) {
                             if (!path->ready) throw ExperimentError("safety fuzz", "no reference path for " + ref_id);
                             fault_run(s, id, mode, loop, fault, cycles, *path, out);
                           }});
        }
      }
    }
  }
}


// The fault-in-motion and loop-switch windows: per context and pair a reference (its own phase)
// and one task per fault. kAll: every fault on every modes x loops pair; kSubset: a few faults on
// the fault_modes.
void add_motion_tasks(const Shared& s, std::vector<FuzzTask>& references, std::vector<FuzzTask>& tasks,
                      std::vector<std::unique_ptr<MotionScenario>>& scenarios) {
  if (s.faults.empty() || !s.o.motion_faults) return;
  static const char* const kSubsetMotionFaults[] = {"nan_q", "stall_50", "wrench_stuck"};
  std::vector<const FaultCase*> faults;
  for (const FaultCase& f : s.faults) {
    const bool in_subset = std::any_of(std::begin(kSubsetMotionFaults), std::end(kSubsetMotionFaults),
                                       [&](const char* name) { return f.name == name; });
    if (s.o.faults == FaultSet::kAll || in_subset) faults.push_back(&f);
  }
  const std::vector<ComplianceMode>& modes = s.o.faults == FaultSet::kAll ? s.o.modes : s.o.fault_modes;
  const bool hand_on_tool_possible = s.plant.ft_sensor_present() && s.model.has_frame("ft_sensor");
  for (const bool with_switch : {false, true}) {
    for (ComplianceMode mode : modes) {
      for (LowLevelMode loop : s.loops) {
        if (with_switch && loop == LowLevelMode::kPosition) continue;  // no switch to make
        auto sc = std::make_unique<MotionScenario>();
        sc->with_switch = with_switch;
        sc->mode = mode;
        sc->loop = loop;
        const std::uint64_t pair_seed = mix_seed(mix_seed(s.o.seed, 0x307104ULL), pair_key(mode, loop));
        sc->key = mix_seed(pair_seed, with_switch ? 0x5717C4ULL : 0x4071014ULL);
        sc->plant_seed = mix_seed(sc->key, 2) >> 2;
        RandomGenerator push_rng(mix_seed(pair_seed, 1), 1);  // the same push in both contexts
        sc->push = draw_motion_push(push_rng, s.model, *s.collision, s.o.motion,
                                    mode == ComplianceMode::kDual && hand_on_tool_possible, SimScene::kToolBody, "ft_sensor");
        RandomGenerator switch_rng(mix_seed(sc->key, 4), 4);
        sc->switch_offset = with_switch ? std::lround(switch_rng.uniform(s.o.motion.min_fault_start_s, s.o.motion.max_fault_start_s) / s.dt) : 0;
        MotionScenario* scenario = sc.get();
        scenarios.push_back(std::move(sc));
        const std::string context = scenario->context();
        const std::string ref_id = context + "-reference/" + pair_id(mode, loop);
        references.push_back({ref_id, 8.0, [&s, ref_id, scenario](TaskOutput& out) { motion_run(s, ref_id, *scenario, nullptr, out); }});
        for (const FaultCase* fault : faults) {
          const std::string id = context + "/" + pair_id(mode, loop) + "/" + fault->name;
          tasks.push_back({id, 3.0, [&s, id, scenario, fault](TaskOutput& out) { motion_run(s, id, *scenario, fault, out); }});
        }
      }
    }
  }
}

// Runs `tasks` on `jobs` threads (the longest first); each task's output lands at its index, so
// the result does not depend on the scheduling. The first error (a ConfigError, say) is rethrown.
class TaskPool {
public:
  TaskPool(std::vector<FuzzTask>& tasks, std::vector<TaskOutput>& outputs, std::ostream* progress, const char* phase)
      : tasks_(tasks), outputs_(outputs), progress_(progress), phase_(phase) {}

  void run(int jobs) {
    order_.resize(tasks_.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
    std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) { return tasks_[a].cost > tasks_[b].cost; });
    outputs_.assign(tasks_.size(), TaskOutput{});
    const int threads = std::max(1, std::min<int>(jobs, static_cast<int>(tasks_.size())));
    std::vector<std::thread> workers;
    for (int t = 1; t < threads; ++t) workers.emplace_back([this] { work(); });
    work();
    for (std::thread& w : workers) w.join();
    if (error_) std::rethrow_exception(error_);
  }

private:
  void work() {
    for (;;) {
      const std::size_t k = next_.fetch_add(1);
      if (k >= order_.size() || failed_.load()) return;
      const std::size_t i = order_[k];
      try {
        tasks_[i].run(outputs_[i]);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        failed_.store(true);
        return;
      }
      report(i);
    }
  }

  void report(std::size_t i) {
    const std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    for (const FuzzRecord& r : outputs_[i].records) {
      if (r.kind == FuzzCaseKind::kFault) ++faults_;
      if (r.kind == FuzzCaseKind::kRandomPush || r.kind == FuzzCaseKind::kLimitPush || r.kind == FuzzCaseKind::kWristFold) ++pushes_;
      if (r.verdict.controller_failure()) ++failures_;
    }
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (progress_ == nullptr || (done_ < tasks_.size() && elapsed < next_print_)) return;
    next_print_ = elapsed + 5.0;
    *progress_ << "safety-fuzz " << phase_ << ": " << done_ << "/" << tasks_.size() << " runs, " << pushes_ << " pushes, "
               << faults_ << " faults, " << failures_ << " controller failures, " << format_fixed(elapsed, 0) << " s"
               << std::endl;
  }

  std::vector<FuzzTask>& tasks_;
  std::vector<TaskOutput>& outputs_;
  std::ostream* progress_;
  const char* phase_;
  std::vector<std::size_t> order_;
  std::atomic<std::size_t> next_{0};
  std::atomic<bool> failed_{false};
  std::mutex mutex_;
  std::exception_ptr error_;
  std::size_t done_ = 0;
  long pushes_ = 0, faults_ = 0, failures_ = 0;
  double next_print_ = 5.0;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Keeps the task `id` only (and the reference a fault run needs); ConfigError when none matches.
void keep_replay(const std::string& id, std::vector<FuzzTask>& references, std::vector<FuzzTask>& tasks) {
  auto named = [&](const FuzzTask& t) { return t.id == id; };
  const bool in_tasks = std::any_of(tasks.begin(), tasks.end(), named);
  const bool in_references = std::any_of(references.begin(), references.end(), named);
  if (!in_tasks && !in_references) {
    throw ConfigError("<safety fuzz options>", "replay", "no run '" + id + "' with these options (see report.md for the ids)");
  }
  std::erase_if(tasks, [&](const FuzzTask& t) { return !named(t); });
  // A fault run needs the reference of its (mode, loop): "fault/<mode>/<loop>/..." -> "reference/<mode>/<loop>",
  // "motion/..." -> "motion-reference/...", "switch/..." -> "switch-reference/...".
  std::string reference = id;
  for (const auto& [prefix, reference_prefix] : {std::pair<std::string, std::string>{"fault/", "reference/"},
                                                 {"motion/", "motion-reference/"}, {"switch/", "switch-reference/"}}) {
    if (id.rfind(prefix, 0) != 0) continue;
    const std::size_t p = prefix.size(), mode_end = id.find('/', p), loop_end = id.find('/', mode_end + 1);
    reference = reference_prefix + id.substr(p, loop_end - p);
  }
  std::erase_if(references, [&](const FuzzTask& t) { return t.id != reference; });
}

void collect(std::vector<TaskOutput>& outputs, SafetyFuzzResult& result) {
  for (TaskOutput& out : outputs) {
    result.runs += out.rigs;
    result.simulated_s += out.simulated_s;
    for (FuzzRecord& r : out.records) result.records.push_back(std::move(r));
  }
}

}  // namespace

long SafetyFuzzResult::controller_failures() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) { return r.verdict.controller_failure(); });
}

long SafetyFuzzResult::invalid_windows() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) { return r.verdict.invalid; });
}

long SafetyFuzzResult::held_command_windows() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) { return r.verdict.held_command; });
}

long SafetyFuzzResult::passes() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) { return r.verdict.passed(); });
}

long SafetyFuzzResult::pushes() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) {
    return r.kind == FuzzCaseKind::kRandomPush || r.kind == FuzzCaseKind::kLimitPush || r.kind == FuzzCaseKind::kWristFold;
  });
}

long SafetyFuzzResult::faults_in(std::string_view context) const {
  return std::count_if(records.begin(), records.end(),
                       [&](const FuzzRecord& r) { return r.kind == FuzzCaseKind::kFault && r.context == context; });
}

long SafetyFuzzResult::faults() const {
  return std::count_if(records.begin(), records.end(), [](const FuzzRecord& r) { return r.kind == FuzzCaseKind::kFault; });
}

SafetyFuzzResult run_safety_fuzz(const SafetyFuzzOptions& o, std::ostream* progress) {
  const auto wall_start = std::chrono::steady_clock::now();
  const std::unique_ptr<Shared> shared = load_shared(o);
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  std::vector<FuzzTask> references, tasks;
  std::vector<std::unique_ptr<ReferencePath>> paths;
  add_push_tasks(*shared, tasks);
  add_targeted_tasks(*shared, tasks);
  add_fault_tasks(*shared, references, tasks, paths);
  std::vector<std::unique_ptr<MotionScenario>> scenarios;
  add_motion_tasks(*shared, references, tasks, scenarios);
  if (!o.replay.empty()) keep_replay(o.replay, references, tasks);
  if (progress) {
    *progress << "safety-fuzz: seed " << o.seed << ", " << references.size() + tasks.size() << " runs (" << shared->faults.size()
              << " fault cases), " << o.jobs << " jobs" << std::endl;
  }
  SafetyFuzzResult result;
  result.skipped_loops = shared->skipped;
  result.skipped_rows = static_cast<int>(o.modes.size() * shared->skipped.size());
  std::vector<TaskOutput> reference_outputs, outputs;
  TaskPool(references, reference_outputs, progress, "references").run(o.jobs);
  TaskPool(tasks, outputs, progress, "runs").run(o.jobs);
  collect(reference_outputs, result);
  collect(outputs, result);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (!o.output_dir.empty()) {
    result.files = write_output_files(o.output_dir, {{"safety_fuzz.csv", safety_fuzz_csv(result)},
                                                     {"report.md", safety_fuzz_report(result, o)}});
  }
  return result;
}

}  // namespace phri
