// ctest-labels: unit
// The ROS 2 bridge (src/phri/ros2/): the checks of its inputs, its status line, and the bridge
// itself against plain Cyclone DDS readers and writers in this process (domains 42, 45, 46, loopback).
// The interop with an independent DDS (Fast DDS) in another process: fastdds_peer.cpp.
#include <phri/ros2/dds_config.hpp>
#include <phri/ros2/input_gate.hpp>
#include <phri/ros2/ros2_bridge.hpp>
#include <phri/ros2/status_text.hpp>

#include <phri/config/config.hpp>
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>
#include <phri/robot/fake_robot.hpp>
#include <phri/ros2/ft_in_robot.hpp>

#include "allocation_counter.hpp"
#include "ros2_messages.h"

#include <dds/dds.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <fstream>
#include <map>
#include <random>
#include <tuple>
#include <vector>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

namespace phri {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

InputLimits limits() {
  InputLimits l;
  l.base_frame = "base_link";
  l.base_in_world = Eigen::Isometry3d::Identity();
  l.base_in_world.translation() = Eigen::Vector3d(1.0, 0.0, 0.5);  // a base away from the world origin
  l.max_reach_m = 1.0;
  l.max_rate_hz = 50.0;
  return l;
}

PoseInput pose(double x, double y, double z, const char* frame = "world") {
  PoseInput p;
  p.frame_id = frame;
  p.position = {x, y, z};
  return p;
}

TEST(InputGate, RefusesWhatIsNotATarget) {
  InputGate gate(limits());
  LiveTarget out;
  EXPECT_EQ(gate.target(pose(kNan, 0.0, 0.5), 0.0, out), InputRefusal::kNotFinite);
  PoseInput inf = pose(1.2, 0.0, 0.5);
  inf.orientation_xyzw[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(gate.target(inf, 1.0, out), InputRefusal::kNotFinite);
  PoseInput half = pose(1.2, 0.0, 0.5);
  half.orientation_xyzw = {0.0, 0.0, 0.0, 0.5};
  EXPECT_EQ(gate.target(half, 2.0, out), InputRefusal::kNotUnitQuaternion);
  EXPECT_EQ(gate.target(pose(-0.001, 0.0, 0.5), 3.0, out), InputRefusal::kOutOfReach);  // 1.001 m from the base at x = 1
  EXPECT_EQ(gate.target(pose(1.2, 0.0, 0.5, "camera_link"), 4.0, out), InputRefusal::kUnknownFrame);
  EXPECT_EQ(gate.accepted(), 0u);
  EXPECT_EQ(gate.refused_total(), 5u);
  EXPECT_EQ(gate.refused(InputRefusal::kNotFinite), 2u);
}

TEST(InputGate, AcceptsAndExpressesInWorld) {
  InputGate gate(limits());
  LiveTarget out;
  // 90 deg about z, a slightly non-unit quaternion (|q| = 1.005): normalised.
  PoseInput p = pose(0.2, 0.1, 0.0, "base_link");
  const double s = std::sqrt(0.5) * 1.005;
  p.orientation_xyzw = {0.0, 0.0, s, s};
  ASSERT_EQ(gate.target(p, 0.0, out), InputRefusal::kNone);
  EXPECT_TRUE(out.position.isApprox(Eigen::Vector3d(1.2, 0.1, 0.5), 1e-15));  // base frame + the base's offset
  EXPECT_NEAR(out.orientation.norm(), 1.0, 1e-15);
  EXPECT_NEAR(Eigen::AngleAxisd(out.orientation).angle(), M_PI / 2, 1e-12);
  ASSERT_EQ(gate.target(pose(1.2, 0.0, 0.5, ""), 1.0, out), InputRefusal::kNone);  // empty frame: world
  EXPECT_EQ(gate.accepted(), 2u);
}

TEST(InputGate, RateLimitAcceptsExactlyMaxRate) {
  InputGate gate(limits());  // 50 Hz: one accepted per 20 ms
  LiveTarget out;
  int accepted = 0;
  for (int k = 0; k < 100000; ++k) {  // a 100 kHz flood for 1 s
    if (gate.target(pose(1.2, 0.0, 0.5), k * 1e-5, out) == InputRefusal::kNone) ++accepted;
  }
  EXPECT_EQ(accepted, 50);  // t = 0, 0.02, ..., 0.98
  EXPECT_EQ(gate.refused(InputRefusal::kTooFast), 100000u - 50u);
}

// The reach bound against forward kinematics: no configuration of the Gen3 within its joint limits
// puts the end effector beyond it, and it is not loose by more than the arm's folded-in offsets.
TEST(InputGate, ReachBoundsForwardKinematics) {
  const Model model = Model::from_urdf_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf");
  const int ee = model.frame_id("end_effector_link");
  const double reach = arm_reach_m(model, ee);
  Data data(model);
  std::mt19937 rng(41);
  double farthest = 0.0;
  Eigen::VectorXd q(model.nq());
  for (int k = 0; k < 20000; ++k) {
    for (int i = 0; i < model.nq(); ++i) {
      const Joint& j = model.joint(i);
      const double lo = j.has_position_limits() ? j.lower : -M_PI, hi = j.has_position_limits() ? j.upper : M_PI;
      q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
    }
    forward_kinematics(model, data, q);
    update_frame_placements(model, data);
    const Eigen::Vector3d p = data.frame_placements[static_cast<std::size_t>(ee)].translation() - model.base_placement().translation();
    farthest = std::max(farthest, p.norm());
  }
  EXPECT_LE(farthest, reach);
  EXPECT_GT(farthest, 0.8 * reach);  // not loose: stretched out, the Gen3 reaches 1.1865 m of the 1.1878 m bound
  RecordProperty("reach_m", std::to_string(reach));
  RecordProperty("farthest_sampled_m", std::to_string(farthest));
}

TEST(InputGate, EventsByName) {
  InputGate gate(limits());
  Event e = Event::kStop;
  EXPECT_EQ(gate.event("self_destruct", 0.0, e), InputRefusal::kUnknownEvent);
  EXPECT_EQ(gate.event("", 0.0, e), InputRefusal::kUnknownEvent);
  EXPECT_EQ(gate.event("Dual_Compliance", 0.0, e), InputRefusal::kUnknownEvent);  // names are exact
  for (int i = 0; i < kEventCount; ++i) {
    ASSERT_EQ(gate.event(kEventNames[static_cast<std::size_t>(i)], 1.0 + i, e), InputRefusal::kNone);
    EXPECT_EQ(code(e), i);
  }
}

TEST(StatusText, KeysInOrderAndValues) {
  LiveSnapshot s;
  s.row.time_s = 3.25;
  s.row.cycle = 3250;
  s.row.compliance_mode = 3;  // dual
  s.row.low_level_loop = 1;   // kinova_torque
  s.row.fsm_state = 1;        // static
  s.row.cycle_time_s = 84.1e-6;
  s.row.error_position_m = 0.00042;
  s.overruns = 2;
  BridgeCounters c;
  c.inputs_accepted = 7;
  c.inputs_refused = 3;
  c.last_refusal = "too_fast";
  char buffer[512];
  const std::size_t n = status_text(s, c, buffer, sizeof buffer);
  const std::string line(buffer, n);
  std::istringstream in(line);
  std::vector<std::string> keys;
  std::map<std::string, std::string> kv;
  for (std::string item; in >> item;) {
    const auto eq = item.find('=');
    ASSERT_NE(eq, std::string::npos) << item;
    keys.push_back(item.substr(0, eq));
    kv[keys.back()] = item.substr(eq + 1);
  }
  const std::vector<std::string> expected = {"t", "cycle", "mode", "touched", "loop", "fsm", "safety", "fault", "ft", "cycle_us",
                                             "overruns", "stiffness", "err_mm", "inputs_accepted", "inputs_refused",
                                             "last_refusal", "snapshots_dropped"};
  EXPECT_EQ(keys, expected);
  EXPECT_EQ(kv["t"], "3.250");
  EXPECT_EQ(kv["cycle"], "3250");
  EXPECT_EQ(kv["mode"], "dual");
  EXPECT_EQ(kv["loop"], "kinova_torque");
  EXPECT_EQ(kv["fsm"], "static");
  EXPECT_EQ(kv["safety"], "normal");
  EXPECT_EQ(kv["cycle_us"], "84.1");
  EXPECT_EQ(kv["overruns"], "2");
  EXPECT_EQ(kv["err_mm"], "0.42");
  EXPECT_EQ(kv["last_refusal"], "too_fast");
  // A short buffer is cut, never overrun.
  char small[16];
  EXPECT_EQ(status_text(s, c, small, sizeof small), 15u);
  EXPECT_EQ(std::string(small), line.substr(0, 15));
}

TEST(Ros2Bridge, NamesOnTheWire) {
  EXPECT_EQ(Ros2Bridge::dds_topic_name("/joint_states"), "rt/joint_states");
  EXPECT_EQ(Ros2Bridge::dds_topic_name("/phri/wrench"), "rt/phri/wrench");
  EXPECT_EQ(std::string(sensor_msgs_msg_dds__JointState__desc.m_typename), "sensor_msgs::msg::dds_::JointState_");
  EXPECT_EQ(std::string(tf2_msgs_msg_dds__TFMessage__desc.m_typename), "tf2_msgs::msg::dds_::TFMessage_");
  EXPECT_TRUE(valid_ros_namespace("/phri"));
  EXPECT_TRUE(valid_ros_namespace("/lab/arm_1"));
  EXPECT_FALSE(valid_ros_namespace("phri"));
  EXPECT_FALSE(valid_ros_namespace("/phri/"));
  EXPECT_FALSE(valid_ros_namespace("/1arm"));
  EXPECT_FALSE(valid_ros_namespace("/a//b"));
  EXPECT_FALSE(valid_ros_namespace("/a b"));
}

// /phri/ft_in as the robot's F/T: the sequence advances only with new samples, the stamp is the
// robot time a sample came (this cycle's time - its age), nothing before the first sample.
TEST(FtInRobot, SequenceAndStampFollowTheSamples) {
  FakeRobot fake;
  TripleBuffer<FtInSample> source;
  FtInRobot robot(fake, source, 8);
  const RobotState& s0 = robot.read();
  EXPECT_FALSE(s0.wrench.valid);
  EXPECT_EQ(s0.wrench.sequence, 0u);
  const auto now_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  };
  FtInSample sample;
  sample.wrench = {1.0, 2.0, 3.0, 0.1, 0.2, 0.3};
  sample.count = 1;
  sample.received_ns = now_ns() - 4000000;  // received 4 ms ago
  source.publish(sample);
  const RobotState& s1 = robot.read();
  EXPECT_TRUE(s1.wrench.valid);
  EXPECT_EQ(s1.wrench.sequence, 1u);
  EXPECT_NEAR(s1.time_s - s1.wrench.stamp_s, 0.004, 0.002);  // its age, give or take the test's own time
  EXPECT_EQ(s1.wrench_sensor[2], 3.0);
  EXPECT_EQ(s1.wrench_sensor[5], 0.3);
  const double stamp = s1.wrench.stamp_s;
  const RobotState& s2 = robot.read();  // no new sample: same sequence and stamp (the supervisor sees it stale later)
  EXPECT_EQ(s2.wrench.sequence, 1u);
  EXPECT_EQ(s2.wrench.stamp_s, stamp);
  sample.count = 2;
  sample.received_ns = now_ns();
  source.publish(sample);
  EXPECT_EQ(robot.read().wrench.sequence, 2u);
  ASSERT_EQ(robot.ages_s().size(), 2u);
  EXPECT_NEAR(robot.ages_s()[0], 0.004, 0.002);
  EXPECT_EQ(robot.samples_seen(), 2u);
}

// The run YAML's ros2: section (configs/demo.yaml documents every key).
TEST(Ros2Config, DemoKeysAndRefusals) {
  const std::string dir = std::string(PHRI_SOURCE_DIR) + "/configs";
  std::ifstream file(dir + "/demo.yaml");
  std::stringstream text;
  text << file.rdbuf();
  const std::string demo = text.str();
  const Config c = Config::from_yaml_string(demo, "demo.yaml", dir);
  EXPECT_FALSE(c.ros2.enabled);
  EXPECT_EQ(c.ros2.topic_namespace, "/phri");
  EXPECT_EQ(c.ros2.joint_states_decimation, 10);
  EXPECT_EQ(c.ros2.discovery, "loopback");
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string y = demo;
    const auto pos = y.find(from);
    if (pos == std::string::npos) throw std::runtime_error("test bug: " + from);
    return y.replace(pos, from.size(), to);
  };
  const Config d = Config::from_yaml_string(with("  domain: -1 ", "  domain: 7 "), "demo.yaml", dir);
  EXPECT_EQ(d.ros2.domain, 7);
  for (const auto& [from, to, key] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"namespace: /phri ", "namespace: /phri/ ", "ros2.namespace"},
           {"  domain: -1 ", "  domain: 233 ", "ros2.domain"},
           {"discovery: loopback ", "discovery: multicast ", "ros2.discovery"},
           {"  decimation: 20 ", "  decimation: 0 ", "ros2.decimation"},
           {"  ft_in: false ", "  ft_in: false\n  typo: 1 ", "ros2"}}) {
    try {
      Config::from_yaml_string(with(from, to), "demo.yaml", dir);
      ADD_FAILURE() << "accepted " << to;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

// ------------------------------------------------------------------------------------ the bridge on DDS
// ctest runs each test in its own process, two at a time: each test its own domain, or they would
// see each other's topics.
int test_domain() {
  const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  if (name == "PublishesSnapshots") return 42;
  if (name == "TakesCheckedInputs") return 45;
  return 46;
}

template <class Done>
bool wait_until(double timeout_s, Done done) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < timeout_s) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

dds_qos_t* reliable_qos() {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 100);
  return qos;
}

class BridgeOnDds : public ::testing::Test {
protected:
  void SetUp() override {
    model_ = std::make_unique<Model>(Model::from_urdf_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf"));
    Ros2Settings s;
    s.enabled = true;
    s.domain = test_domain();
    s.joint_states_decimation = 1;
    s.decimation = 1;
    s.max_input_rate_hz = 1000.0;
    bridge_ = std::make_unique<Ros2Bridge>(s, *model_, model_->frame_id("end_effector_link"));
    participant_ = dds_create_participant(test_domain(), nullptr, nullptr);
    ASSERT_GT(participant_, 0);
    dds_qos_t* qos = reliable_qos();
    joints_ = dds_create_reader(participant_, topic(&sensor_msgs_msg_dds__JointState__desc, "rt/joint_states"), qos, nullptr);
    tf_ = dds_create_reader(participant_, topic(&tf2_msgs_msg_dds__TFMessage__desc, "rt/tf"), qos, nullptr);
    target_ = dds_create_writer(participant_, topic(&geometry_msgs_msg_dds__PoseStamped__desc, "rt/phri/target_pose"), qos, nullptr);
    event_ = dds_create_writer(participant_, topic(&std_msgs_msg_dds__String__desc, "rt/phri/event"), qos, nullptr);
    dds_delete_qos(qos);
    ASSERT_GT(joints_, 0);
    ASSERT_GT(target_, 0);
    bridge_->start();
    ASSERT_TRUE(wait_until(5.0, [&] { return matched(joints_, false) && matched(tf_, false) && matched(target_, true) && matched(event_, true); }));
  }
  void TearDown() override {
    if (bridge_) bridge_->stop();
    if (participant_ > 0) dds_delete(participant_);
  }
  dds_entity_t topic(const dds_topic_descriptor_t* type, const char* name) { return dds_create_topic(participant_, type, name, nullptr, nullptr); }
  static bool matched(dds_entity_t e, bool writer) {
    if (writer) {
      dds_publication_matched_status_t st;
      return dds_get_publication_matched_status(e, &st) == 0 && st.current_count > 0;
    }
    dds_subscription_matched_status_t st;
    return dds_get_subscription_matched_status(e, &st) == 0 && st.current_count > 0;
  }

  std::unique_ptr<Model> model_;
  std::unique_ptr<Ros2Bridge> bridge_;
  dds_entity_t participant_ = 0, joints_ = 0, tf_ = 0, target_ = 0, event_ = 0;
};

// Snapshots handed over as the loop does arrive on /joint_states with their values, and /tf is the
// model's forward kinematics, link by link.
TEST_F(BridgeOnDds, PublishesSnapshots) {
  LiveSnapshot s;
  s.dof = 7;
  for (int k = 0; k < 20; ++k) {
    s.row.cycle = k;
    for (int i = 0; i < 7; ++i) {
      s.row.q[static_cast<std::size_t>(i)] = 0.1 * i + 0.01 * k;
      s.row.qd[static_cast<std::size_t>(i)] = -0.2 * i;
      s.row.tau_s[static_cast<std::size_t>(i)] = 1.5 * i + k;
    }
    ASSERT_TRUE(bridge_->observer().publish(s));
  }
  int received = 0;
  bool values = true;
  int tf_received = 0;
  double tf_worst = 0.0;
  Data data(*model_);
  ASSERT_TRUE(wait_until(5.0, [&] {
    void* samples[8] = {};
    dds_sample_info_t infos[8];
    const int n = dds_take(joints_, samples, infos, 8, 8);
    for (int j = 0; j < n; ++j) {
      const auto* m = static_cast<const sensor_msgs_msg_dds__JointState_*>(samples[j]);
      const int k = received++;
      values = values && m->name._length == 7 && std::string(m->name._buffer[6]) == "joint_7" && m->position._length == 7;
      for (int i = 0; values && i < 7; ++i) {
        values = m->position._buffer[i] == 0.1 * i + 0.01 * k && m->velocity._buffer[i] == -0.2 * i && m->effort._buffer[i] == 1.5 * i + k;
      }
    }
    if (n > 0) dds_return_loan(joints_, samples, n);
    const int t = dds_take(tf_, samples, infos, 8, 8);
    for (int j = 0; j < t; ++j) {
      const auto* m = static_cast<const tf2_msgs_msg_dds__TFMessage_*>(samples[j]);
      Eigen::VectorXd q(7);
      for (int i = 0; i < 7; ++i) q[i] = 0.1 * i + 0.01 * tf_received;
      ++tf_received;
      forward_kinematics(*model_, data, q);
      Eigen::Isometry3d x = model_->base_placement();
      for (std::uint32_t b = 0; b < m->transforms._length; ++b) {
        const auto& tr = m->transforms._buffer[b].transform;
        Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
        step.linear() = Eigen::Quaterniond(tr.rotation.w, tr.rotation.x, tr.rotation.y, tr.rotation.z).toRotationMatrix();
        step.translation() = Eigen::Vector3d(tr.translation.x, tr.translation.y, tr.translation.z);
        x = x * step;
        tf_worst = std::max(tf_worst, (x.translation() - data.body_placements[b].translation()).norm());
      }
      values = values && m->transforms._length == 7;
    }
    if (t > 0) dds_return_loan(tf_, samples, t);
    return received >= 20 && tf_received >= 20;
  }));
  EXPECT_EQ(received, 20);
  EXPECT_TRUE(values);
  EXPECT_LT(tf_worst, 1e-12);
  bridge_->stop();
  EXPECT_EQ(bridge_->stats().published[0], 20u);
}

// Inputs reach the loop's queue only when they pass the gate.
TEST_F(BridgeOnDds, TakesCheckedInputs) {
  geometry_msgs_msg_dds__PoseStamped_ pose{};
  char world[] = "world";
  pose.header.frame_id = world;
  pose.pose.position = {0.4, 0.1, 0.3};
  pose.pose.orientation = {0.0, 0.0, 0.0, 1.0};
  ASSERT_EQ(dds_write(target_, &pose), 0);
  pose.pose.position.x = kNan;
  ASSERT_EQ(dds_write(target_, &pose), 0);
  char unknown[] = "self_destruct", dual[] = "dual_compliance";
  std_msgs_msg_dds__String_ event{unknown};
  ASSERT_EQ(dds_write(event_, &event), 0);
  event.data = dual;
  ASSERT_EQ(dds_write(event_, &event), 0);
  std::vector<LiveCommand> commands;
  ASSERT_TRUE(wait_until(5.0, [&] {
    for (LiveCommand c; bridge_->input().receive(c);) commands.push_back(c);
    return commands.size() >= 2 && bridge_->stats().refused_total() >= 2;
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (LiveCommand c; bridge_->input().receive(c);) commands.push_back(c);
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].kind, LiveCommand::Kind::kTarget);
  EXPECT_EQ(commands[0].target.position, Eigen::Vector3d(0.4, 0.1, 0.3));
  EXPECT_EQ(commands[1].kind, LiveCommand::Kind::kEvent);
  EXPECT_EQ(commands[1].event, Event::kDualCompliance);
  const Ros2BridgeStats st = bridge_->stats();
  EXPECT_EQ(st.refused[static_cast<std::size_t>(InputRefusal::kNotFinite)], 1u);
  EXPECT_EQ(st.refused[static_cast<std::size_t>(InputRefusal::kUnknownEvent)], 1u);
}

// The control thread's side of the bridge (snapshots out, commands in, the F/T sample) allocates
// nothing and never waits, while another participant floods /phri/target_pose: the flood is
// refused at the rate limit on the bridge's thread and the loop's queue only sees what passed.
TEST_F(BridgeOnDds, ControlSideAllocatesNothingUnderAFlood) {
  std::atomic<bool> flooding{true};
  std::atomic<int> sent{0};
  std::thread flood([&] {
    geometry_msgs_msg_dds__PoseStamped_ pose{};
    char world[] = "world";
    pose.header.frame_id = world;
    pose.pose.position = {0.4, 0.1, 0.3};
    pose.pose.orientation = {0.0, 0.0, 0.0, 1.0};
    while (flooding) {
      dds_write(target_, &pose);
      ++sent;
    }
  });
  FakeRobot fake;
  FtInRobot robot(fake, bridge_->ft_in(), 16);
  LiveSnapshot s;
  s.dof = 7;
  int commands = 0, published = 0;
  const auto t0 = std::chrono::steady_clock::now();
  {
    const test::AllocationCounter count;
    for (int k = 0; k < 1000; ++k) {  // one second of 1 kHz cycles
      s.row.cycle = k;
      published += bridge_->observer().publish(s) ? 1 : 0;
      for (LiveCommand c; bridge_->input().receive(c);) ++commands;
      robot.read();
      std::this_thread::sleep_for(std::chrono::microseconds(1000));
    }
    EXPECT_EQ(count.allocations(), 0u);
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  flooding = false;
  flood.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (LiveCommand c; bridge_->input().receive(c);) ++commands;
  const Ros2BridgeStats st = bridge_->stats();
  EXPECT_GT(sent.load(), 10000);
  EXPECT_GT(st.refused[static_cast<std::size_t>(InputRefusal::kTooFast)], 1000u);
  EXPECT_LE(commands, 1000.0 * (elapsed + 0.1) + 1);  // max_input_rate_hz = 1000 in this fixture
  EXPECT_EQ(static_cast<std::uint64_t>(commands), st.targets);
  EXPECT_GT(published, 900);  // the bridge kept up: at most a few snapshots dropped
}

}  // namespace
}  // namespace phri
