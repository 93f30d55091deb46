// ctest-labels: unit
// phri::KortexRobot over phri::KortexEmulator (issue 18), on phri::FakeRobot as the plant (a
// deterministic unit-inertia arm: exact torques, no MuJoCo): the Kortex units and wrapping, the
// torque's sign, frame_id / command_id with the 16-bit wrap, the measured position echoed in
// the torque and current modes and the emulator's following-error fault beyond 5 deg, the mode
// switch sequence and its way back, current = tau / (K_T G_r), fault and warning bits, the
// watchdog and the session timeout, the start-up refusals (one line each), communication loss
// and the allocation-free cycle.
#include <phri/core/error.hpp>
#include <phri/hardware/kortex_emulator.hpp>
#include <phri/hardware/kortex_robot.hpp>
#include <phri/hardware/kortex_units.hpp>
#include <phri/robot/fake_robot.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using phri::KortexEmulator;
using phri::KortexRobot;
namespace kortex = phri::kortex;
constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Gen3-like: joints 1, 3, 5, 7 continuous, 2, 4, 6 limited; K_T G_r 11 (large), 7.6 (small).
phri::KortexRobotSettings gen3_like() {
  phri::KortexRobotSettings s;
  s.dof = 7;
  s.position_lower_rad.resize(7);
  s.position_upper_rad.resize(7);
  s.position_lower_rad << -kInf, -2.24, -kInf, -2.57, -kInf, -2.09, -kInf;
  s.position_upper_rad << kInf, 2.24, kInf, 2.57, kInf, 2.09, kInf;
  s.torque_per_amp_Nm_per_A.resize(7);
  s.torque_per_amp_Nm_per_A << 11, 11, 11, 11, 7.6, 7.6, 7.6;
  s.log = nullptr;
  return s;
}

Eigen::VectorXd start_pose() {
  Eigen::VectorXd q(7);
  q << 3.0, 0.26, kPi - 1e-9, -2.27, -0.4, 0.96, 1.57;  // joint 3 at pi, where readings flip sign
  return q;
}

// The plant, the emulated arm on it and (made by start()) the robot.
struct Rig {
  explicit Rig(Eigen::VectorXd q0 = start_pose(), phri::KortexEmulatorSettings emulator = {})
      : plant(fake_settings(q0)), arm(plant, plant.state(), emulator) {}

  static phri::FakeRobotSettings fake_settings(const Eigen::VectorXd& q0) {
    phri::FakeRobotSettings s;
    s.initial_q_rad = q0;
    s.torque_per_amp_Nm_per_A = gen3_like().torque_per_amp_Nm_per_A;
    return s;
  }
  KortexRobot& start(phri::KortexRobotSettings settings = gen3_like()) {
    settings.reference_q_rad = plant.state().q_rad;
    robot = std::make_unique<KortexRobot>(arm, settings);
    return *robot;
  }
  phri::RobotCommand torque(double tau0 = 0.0) {
    phri::RobotCommand c(7);
    c.mode = phri::LowLevelMode::kKinovaTorque;
    c.tau_Nm[0] = tau0;
    return c;
  }

  phri::FakeRobot plant;
  KortexEmulator arm;
  std::unique_ptr<KortexRobot> robot;
};

std::vector<std::string> describe(const std::vector<KortexEmulator::Call>& calls, std::size_t from = 0) {
  std::vector<std::string> out;
  for (std::size_t k = from; k < calls.size(); ++k) {
    const KortexEmulator::Call& c = calls[k];
    switch (c.kind) {
      case KortexEmulator::CallKind::kCreateSessions: out.push_back("CreateSession"); break;
      case KortexEmulator::CallKind::kCloseSessions: out.push_back("CloseSession"); break;
      case KortexEmulator::CallKind::kActuatorCount: out.push_back("GetActuatorCount"); break;
      case KortexEmulator::CallKind::kArmState: out.push_back("GetArmState"); break;
      case KortexEmulator::CallKind::kServoingMode: out.push_back("GetServoingMode"); break;
      case KortexEmulator::CallKind::kSetServoingMode:
        out.push_back("SetServoingMode " + std::string(kortex::to_string(static_cast<kortex::ServoingMode>(c.value))));
        break;
      case KortexEmulator::CallKind::kSetControlMode:
        out.push_back("SetControlMode " + std::to_string(c.actuator + 1) + " " +
                      std::string(kortex::to_string(static_cast<kortex::ControlMode>(c.value))));
        break;
      case KortexEmulator::CallKind::kRefreshFeedback: out.push_back("RefreshFeedback"); break;
      default: out.push_back("other"); break;
    }
  }
  return out;
}

std::vector<std::string> all_actuators(const std::string& mode) {
  std::vector<std::string> out;
  for (int i = 1; i <= 7; ++i) out.push_back("SetControlMode " + std::to_string(i) + " " + mode);
  return out;
}

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// ---------------------------------------------------------------------------- units

TEST(KortexUnits, CommandDegreesAreWrappedIntoZeroTo360) {
  EXPECT_NEAR(kortex::command_degrees(-0.1), 360.0 - 0.1 * 180.0 / kPi, 1e-4);
  EXPECT_EQ(kortex::command_degrees(2.0 * kPi), 0.0f);
  EXPECT_NEAR(kortex::command_degrees(7.0 * kPi / 2.0), 270.0, 1e-4);
  for (double q : {-1e-12, -1e-7, 2.0 * kPi - 1e-9, -4.0 * kPi, 100.0}) {
    const float d = kortex::command_degrees(q);
    EXPECT_GE(d, 0.0f) << q;
    EXPECT_LT(d, 360.0f) << q;
  }
}

TEST(KortexUnits, FeedbackDegreesMapToMinusPiPi) {
  EXPECT_NEAR(kortex::feedback_radians(270.0), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(kortex::feedback_radians(180.0), kPi, 1e-12);
  EXPECT_NEAR(kortex::feedback_radians(180.5), -kPi + 0.5 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(kortex::feedback_radians(0.0), 0.0, 1e-15);
  EXPECT_NEAR(kortex::feedback_radians(359.0), -kPi / 180.0, 1e-12);
  // a continuous joint followed across the +-180 deg seam, both ways
  EXPECT_NEAR(kortex::unwrap_near(3.1, kortex::feedback_radians(181.0)), 181.0 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(kortex::unwrap_near(-3.1, kortex::feedback_radians(179.0)), -181.0 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(kortex::unwrap_near(4.0 * kPi + 0.1, kortex::feedback_radians(10.0)), 4.0 * kPi + 10.0 * kPi / 180.0, 1e-12);
}

TEST(KortexUnits, FrameIdWrapsAt16Bits) {
  EXPECT_EQ(kortex::next_frame_id(0), 1u);
  EXPECT_EQ(kortex::next_frame_id(65534), 65535u);
  EXPECT_EQ(kortex::next_frame_id(65535), 0u);
}

TEST(KortexUnits, MotorCurrentIsTorqueOverKtGr) {
  EXPECT_DOUBLE_EQ(kortex::motor_current_for_torque(5.5, 0.11 * 100.0), 0.5);  // large actuator
  EXPECT_DOUBLE_EQ(kortex::motor_current_for_torque(-3.8, 0.076 * 100.0), -0.5);  // small actuator
}

// ---------------------------------------------------------------------------- the robot on the emulator

TEST(KortexRobot, StateMatchesThePlantInRadiansWithContinuousJointsUnwrapped) {
  Rig rig;
  KortexRobot& robot = rig.start();
  const phri::RobotState& s = robot.read();
  EXPECT_LT((s.q_rad - rig.plant.true_q()).cwiseAbs().maxCoeff(), 1e-5);  // float degrees: ~1e-7 rad
  EXPECT_GT(s.q_rad[2], 3.0);  // joint 3 at pi stays at +pi (the reference posture), not -pi
  for (const kortex::ActuatorFeedback& a : robot.feedback().actuators) {
    EXPECT_GE(a.position_deg, 0.0f);
    EXPECT_LT(a.position_deg, 360.0f);
  }
  // drive joint 1 (at 3.0 rad) through +pi: the reading wraps to -180 deg, q does not jump
  phri::RobotCommand c = rig.torque(2.0);
  double previous = s.q_rad[0];
  double largest_step = 0.0;
  for (int k = 0; k < 600; ++k) {
    ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
    const phri::RobotState& r = robot.read();
    largest_step = std::max(largest_step, std::abs(r.q_rad[0] - previous));
    previous = r.q_rad[0];
  }
  EXPECT_GT(previous, kPi + 0.1);
  EXPECT_LT(largest_step, 0.01);
  EXPECT_GT(robot.feedback().actuators[0].position_deg, 180.0f);  // the arm reports 190-odd deg...
  EXPECT_LT(kortex::feedback_radians(robot.feedback().actuators[0].position_deg), 0.0);  // ...which is -170-odd
  EXPECT_NEAR(previous, rig.plant.true_q()[0], 1e-5);
  EXPECT_FALSE(robot.state().fault);
}

TEST(KortexRobot, MeasuredTorqueSignIsFlippedBack) {
  Rig rig;
  KortexRobot& robot = rig.start();
  robot.read();
  ASSERT_EQ(robot.write(rig.torque(2.0)), phri::WriteStatus::kOk);
  robot.read();  // the switch to TORQUE, then the first torque cycle
  ASSERT_EQ(robot.write(rig.torque(2.0)), phri::WriteStatus::kOk);
  const phri::RobotState& s = robot.read();
  EXPECT_NEAR(robot.command().actuators[0].torque_joint_Nm, 2.0f, 1e-6);
  EXPECT_NEAR(robot.feedback().actuators[0].torque_Nm, -2.0f, 1e-5);  // the arm reports it reversed
  EXPECT_NEAR(s.tau_sensor_Nm[0], 2.0, 1e-5);                         // phri: the commanded direction
  EXPECT_NEAR(rig.plant.state().tau_sensor_Nm[0], 2.0, 1e-9);
}

TEST(KortexRobot, FrameAndCommandIdsIncrementAndWrapAt65535) {
  Rig rig;
  KortexRobot& robot = rig.start();
  std::uint32_t previous = robot.command().frame_id;
  bool wrapped = false;
  for (int k = 0; k < 65540; ++k) {
    robot.read();
    const std::uint32_t id = robot.command().frame_id;
    ASSERT_EQ(id, (previous + 1) % 65536) << k;
    wrapped = wrapped || (previous == 65535 && id == 0);
    previous = id;
    for (const kortex::ActuatorCommand& a : robot.command().actuators) ASSERT_EQ(a.command_id, id);
    ASSERT_EQ(robot.feedback().frame_id, id);  // the arm echoes the frame it applied
    ASSERT_EQ(rig.arm.last_command().actuators[6].command_id, id);
  }
  EXPECT_TRUE(wrapped);
}

TEST(KortexRobot, TorqueAndCurrentModesEchoTheMeasuredPosition) {
  Rig rig;
  KortexRobot& robot = rig.start();
  for (phri::LowLevelMode mode : {phri::LowLevelMode::kKinovaTorque, phri::LowLevelMode::kCurrent,
                                  phri::LowLevelMode::kKinovaTorqueHighVelocity}) {
    for (int k = 0; k < 50; ++k) {
      robot.read();
      phri::RobotCommand c(7);
      c.mode = mode;
      c.tau_Nm.setConstant(0.5);
      c.current_A.setConstant(0.05);
      ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
      for (int i = 0; i < 7; ++i) {
        ASSERT_EQ(robot.command().actuators[static_cast<std::size_t>(i)].position_deg,
                  robot.feedback().actuators[static_cast<std::size_t>(i)].position_deg);
      }
    }
  }
  robot.read();
  EXPECT_EQ(rig.arm.counters().following_errors, 0u);
  EXPECT_FALSE(robot.state().fault);
}

TEST(KortexRobot, CommandCarriesCurrentAsTorqueOverKtGrAndBack) {
  Rig rig;
  KortexRobot& robot = rig.start();
  robot.read();
  phri::RobotCommand c = rig.torque();
  c.tau_Nm << 5.5, 0, 0, 0, 3.8, 0, 0;
  ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
  EXPECT_NEAR(robot.command().actuators[0].current_motor_A, 0.5, 1e-6);  // 5.5 / (0.11 x 100)
  EXPECT_NEAR(robot.command().actuators[4].current_motor_A, 0.5, 1e-6);  // 3.8 / (0.076 x 100)
  c.mode = phri::LowLevelMode::kCurrent;
  c.current_A << 0.5, 0, 0, 0, -0.25, 0, 0;
  ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
  EXPECT_NEAR(robot.command().actuators[0].torque_joint_Nm, 5.5, 1e-5);
  EXPECT_NEAR(robot.command().actuators[4].torque_joint_Nm, -1.9, 1e-5);
  robot.read();
  EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kCurrent);
  EXPECT_EQ(rig.arm.plant_command().mode, phri::LowLevelMode::kCurrent);
  EXPECT_NEAR(rig.arm.plant_command().current_A[4], -0.25, 1e-7);
}

TEST(KortexRobot, ModeSwitchSequenceAndTheWayBack) {
  Rig rig;
  KortexRobot& robot = rig.start();
  const std::vector<std::string> start = std::vector<std::string>{
      "CreateSession", "GetActuatorCount", "GetArmState", "SetServoingMode SINGLE_LEVEL_SERVOING",
      "SetServoingMode LOW_LEVEL_SERVOING", "RefreshFeedback"} + all_actuators("POSITION");
  EXPECT_EQ(describe(rig.arm.calls()), start);
  EXPECT_EQ(rig.arm.servoing(), kortex::ServoingMode::kLowLevel);
  robot.read();
  robot.write(rig.torque());
  robot.read();
  EXPECT_EQ(robot.state().mode, phri::LowLevelMode::kKinovaTorque);
  phri::RobotCommand hv = rig.torque();
  hv.mode = phri::LowLevelMode::kKinovaTorqueHighVelocity;
  robot.write(hv);
  robot.read();
  robot.write(hv);  // same mode: no call
  robot.read();
  EXPECT_EQ(robot.health().mode_switches, 2u);
  const std::size_t before_exit = rig.arm.calls().size();
  rig.robot.reset();  // the destructor
  const std::vector<std::string> exit_calls{"SetServoingMode SINGLE_LEVEL_SERVOING", "CloseSession"};
  EXPECT_EQ(describe(rig.arm.calls(), start.size()),
            all_actuators("TORQUE") + all_actuators("TORQUE_HIGH_VELOCITY") + all_actuators("POSITION") + exit_calls);
  EXPECT_EQ(before_exit, start.size() + 14);
  EXPECT_EQ(rig.arm.servoing(), kortex::ServoingMode::kSingleLevel);
  EXPECT_FALSE(rig.arm.sessions_open());
}

TEST(KortexRobot, RefusesWhatTheArmCannotDo) {
  Rig rig;
  KortexRobot& robot = rig.start();
  robot.read();
  phri::RobotCommand c = rig.torque();
  c.mode = phri::LowLevelMode::kTorque;  // a generic drive's plain torque: no Kortex mode
  EXPECT_EQ(robot.write(c), phri::WriteStatus::kInvalidMode);
  c.mode = phri::LowLevelMode::kKinovaTorque;
  c.tau_Nm[2] = std::nan("");
  EXPECT_EQ(robot.write(c), phri::WriteStatus::kNotFinite);
  c.tau_Nm.resize(6);
  EXPECT_EQ(robot.write(c), phri::WriteStatus::kSizeMismatch);
  phri::RobotCommand p(7);
  p.q_rad = rig.plant.true_q();
  p.q_rad[1] = 2.5;  // beyond joint 2's 2.24 rad
  EXPECT_EQ(robot.write(p), phri::WriteStatus::kOutOfRange);
  EXPECT_EQ(robot.read().rejected_writes, 4u);
}

// ---------------------------------------------------------------------------- emulator behaviour

TEST(KortexEmulator, FollowingErrorBeyondFiveDegreesFaultsAndHolds) {
  Rig rig;
  KortexRobot& robot = rig.start();
  robot.read();
  robot.write(rig.torque());
  robot.read();  // now in TORQUE
  kortex::CyclicCommand c = robot.command();
  kortex::CyclicFeedback f = robot.feedback();
  c.actuators[3].position_deg += 4.0f;  // a warning (> 3 deg), no fault
  ASSERT_TRUE(rig.arm.refresh(c, f).ok());
  EXPECT_EQ(f.actuators[3].fault_bank_a, 0u);
  EXPECT_EQ(f.actuators[3].warning_bank_a, kortex::safety_bit::kFollowingError);
  c.actuators[3].position_deg += 2.0f;  // 6 deg
  ASSERT_TRUE(rig.arm.refresh(c, f).ok());
  EXPECT_EQ(f.actuators[3].fault_bank_a, kortex::safety_bit::kFollowingError);
  EXPECT_EQ(f.base.active_state, kortex::ArmState::kInFault);
  EXPECT_TRUE(rig.arm.holding());
  EXPECT_EQ(rig.arm.plant_command().mode, phri::LowLevelMode::kPosition);
  // the robot maps it: fault flag, the bank, and commands refused
  const phri::RobotState& s = robot.read();
  EXPECT_TRUE(s.fault);
  EXPECT_TRUE(robot.health().arm_fault);
  EXPECT_EQ(robot.health().fault_bank_a[3], kortex::safety_bit::kFollowingError);
  EXPECT_EQ(robot.write(rig.torque()), phri::WriteStatus::kFault);
  // ClearFaults: POSITION again, commands accepted
  ASSERT_TRUE(rig.arm.clear_faults().ok());
  EXPECT_EQ(rig.arm.control_mode(3), kortex::ControlMode::kPosition);
  EXPECT_EQ(rig.arm.fault_bank_a(3), 0u);
}

TEST(KortexEmulator, RefreshOnlyInLowLevelServoingWithASession) {
  Rig rig;
  kortex::CyclicCommand c;
  c.actuators.resize(7);
  kortex::CyclicFeedback f;
  f.actuators.resize(7);
  EXPECT_EQ(rig.arm.refresh(c, f).sub_code, kortex::sub_error::kInvalidSession);
  ASSERT_TRUE(rig.arm.create_sessions({}).ok());
  EXPECT_EQ(rig.arm.refresh(c, f).sub_code, kortex::sub_error::kWrongServoingMode);  // single level at boot
  ASSERT_TRUE(rig.arm.set_servoing_mode(kortex::ServoingMode::kLowLevel).ok());
  ASSERT_TRUE(rig.arm.refresh_feedback(f).ok());
  for (int i = 0; i < 7; ++i) c.actuators[static_cast<std::size_t>(i)].position_deg = f.actuators[static_cast<std::size_t>(i)].position_deg;
  EXPECT_TRUE(rig.arm.refresh(c, f).ok());
  EXPECT_EQ(rig.arm.set_control_mode(0, kortex::ControlMode::kVelocity).sub_code, kortex::sub_error::kInvalidParam);
}

TEST(KortexEmulator, WatchdogTripsAfterTenMillisecondsWithoutACommand) {
  Rig rig;
  KortexRobot& robot = rig.start();
  robot.read();
  robot.write(rig.torque(1.0));
  robot.read();
  rig.arm.run_idle(0.009);  // within the watchdog
  EXPECT_EQ(rig.arm.counters().watchdog_trips, 0u);
  robot.read();
  EXPECT_FALSE(robot.state().fault);
  rig.arm.run_idle(0.012);
  EXPECT_EQ(rig.arm.counters().watchdog_trips, 1u);
  EXPECT_TRUE(rig.arm.holding());
  EXPECT_EQ(rig.arm.plant_command().mode, phri::LowLevelMode::kPosition);  // brake / hold
  const phri::RobotState& s = robot.read();
  EXPECT_TRUE(s.fault);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(robot.health().fault_bank_a[static_cast<std::size_t>(i)], kortex::safety_bit::kWatchdogTriggered);
}

TEST(KortexEmulator, SessionClosesAfterItsInactivityTimeout) {
  Rig rig;
  phri::KortexRobotSettings settings = gen3_like();
  settings.session.session_inactivity_timeout_ms = 100;
  KortexRobot& robot = rig.start(settings);
  for (int k = 0; k < 200; ++k) robot.read();  // Refresh keeps it alive
  EXPECT_TRUE(rig.arm.sessions_open());
  rig.arm.run_idle(0.099);
  EXPECT_TRUE(rig.arm.sessions_open());
  rig.arm.run_idle(0.002);
  EXPECT_FALSE(rig.arm.sessions_open());
  EXPECT_EQ(rig.arm.counters().session_timeouts, 1u);
  robot.read();
  EXPECT_EQ(robot.health().last_failure.sub_code, kortex::sub_error::kInvalidSession);
}

// ---------------------------------------------------------------------------- faults, warnings, link

TEST(KortexRobot, FaultAndWarningBitsReachTheState) {
  Rig rig;
  std::FILE* log = std::tmpfile();
  phri::KortexRobotSettings settings = gen3_like();
  settings.log = log;
  KortexRobot& robot = rig.start(settings);
  rig.arm.inject_warning(2, kortex::safety_bit::kMaximumVelocity);
  const phri::RobotState& s = robot.read();
  EXPECT_FALSE(s.fault);
  EXPECT_TRUE(robot.health().warning);
  EXPECT_EQ(robot.health().warning_bank_a[2], kortex::safety_bit::kMaximumVelocity);
  rig.arm.inject_fault(4, kortex::safety_bit::kMaximumTorque);
  for (int k = 0; k < 3; ++k) robot.read();
  EXPECT_TRUE(robot.state().fault);
  EXPECT_EQ(robot.health().fault_bank_a[4], kortex::safety_bit::kMaximumTorque);
  EXPECT_EQ(robot.health().arm_state, kortex::ArmState::kInFault);
  EXPECT_EQ(robot.write(rig.torque(3.0)), phri::WriteStatus::kFault);
  for (std::size_t i = 0; i < 7; ++i) {  // the measured pose, no torque, from the fault on
    EXPECT_EQ(robot.command().actuators[i].torque_joint_Nm, 0.0f);
    EXPECT_EQ(robot.command().actuators[i].position_deg, robot.feedback().actuators[i].position_deg);
  }
  std::rewind(log);
  char text[512] = {};
  const std::size_t n = std::fread(text, 1, sizeof text - 1, log);
  std::fclose(log);
  const std::string logged(text, n);
  EXPECT_EQ(std::count(logged.begin(), logged.end(), '\n'), 1) << logged;  // once
  EXPECT_NE(logged.find("actuator 5, fault bank A 0x20"), std::string::npos) << logged;
  EXPECT_EQ(kortex::safety_bits_to_string(0x800021u), "following_error|maximum_torque|watchdog_triggered");
}

TEST(KortexRobot, CommunicationLossHoldsThePoseInPositionAndStopsTorque) {
  for (int scenario = 0; scenario < 3; ++scenario) {
    SCOPED_TRACE(scenario);
    Rig rig;
    KortexRobot& robot = rig.start();
    for (int k = 0; k < 20; ++k) {
      robot.read();
      robot.write(rig.torque(0.3));
    }
    robot.read();
    ASSERT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kTorque);
    if (scenario == 0) rig.arm.set_packet_loss(1.0, 7);  // every packet lost: 3 failures
    if (scenario == 1) rig.arm.stall_next_refresh(0.005);  // one 5 ms stall
    if (scenario == 2) rig.arm.drop_session();
    for (int k = 0; k < 3; ++k) {
      robot.write(rig.torque(0.3));
      robot.read();
    }
    EXPECT_TRUE(robot.health().link_lost);
    EXPECT_TRUE(robot.state().fault);
    EXPECT_EQ(robot.write(rig.torque(0.3)), phri::WriteStatus::kFault);
    for (const kortex::ActuatorCommand& a : robot.command().actuators) EXPECT_EQ(a.torque_joint_Nm, 0.0f);
    if (scenario != 2) {  // the TCP link still answers: POSITION at the measured pose
      EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kPosition);
      EXPECT_EQ(robot.command().actuators[0].position_deg, robot.feedback().actuators[0].position_deg);
    }
  }
}

// A degraded link: isolated losses are ridden through (each one stale sample for the supervisor),
// but more than 0.5 % of the last 5 s of Refresh calls failing asks for a safe stop, with the count
// in the logged line: the link still carries the brake, then the position hold, and from that hold
// on torque is refused. Losses one at a time (never two in a row, never 5 ms of silence).
TEST(KortexRobot, SustainedPacketLossStopsTorqueButIsolatedLossesDoNot) {
  auto lose_every = [](Rig& rig, KortexRobot& robot, int period, int cycles) {
    for (int k = 1; k <= cycles && !robot.health().link_lost; ++k) {
      rig.arm.set_packet_loss(k % period == 0 ? 1.0 : 0.0, 7);
      robot.write(rig.torque(0.3));
      robot.read();
    }
  };
  std::FILE* log = std::tmpfile();
  phri::KortexRobotSettings settings = gen3_like();
  settings.log = log;
  Rig rig;
  KortexRobot& robot = rig.start(settings);
  robot.read();
  // One loss every 200 cycles for 10 s: 25 in any 5 s, the budget.
  lose_every(rig, robot, 200, 10000);
  EXPECT_FALSE(robot.health().link_lost);
  EXPECT_EQ(robot.health().failed_refreshes, 50u);
  EXPECT_EQ(robot.health().most_losses_in_window, 25);
  EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kTorque);
  // One every 100 cycles (1 %): the 26th within 5 s asks to stop, 2.5 s on at the latest.
  for (int k = 1; k <= 5000 && !robot.health().link_degraded; ++k) {
    rig.arm.set_packet_loss(k % 100 == 0 ? 1.0 : 0.0, 7);
    robot.write(rig.torque(0.3));
    robot.read();
  }
  rig.arm.set_packet_loss(0.0, 7);
  EXPECT_TRUE(robot.health().link_degraded);
  EXPECT_FALSE(robot.health().link_lost);
  EXPECT_EQ(robot.health().losses_in_window, 26);
  EXPECT_EQ(robot.health().longest_failure_run, 1);
  EXPECT_TRUE(robot.state().stop_requested);
  EXPECT_FALSE(robot.state().fault);  // the samples stay good: the brake runs on them
  // The brake (torque) still reaches the arm...
  EXPECT_EQ(robot.write(rig.torque(0.2)), phri::WriteStatus::kOk);
  robot.read();
  EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kTorque);
  EXPECT_FLOAT_EQ(rig.arm.last_command().actuators[0].torque_joint_Nm, 0.2f);
  // ...then the position hold; after it, torque is refused.
  phri::RobotCommand hold(7);
  hold.mode = phri::LowLevelMode::kPosition;
  hold.q_rad = robot.state().q_rad;
  EXPECT_EQ(robot.write(hold), phri::WriteStatus::kOk);
  robot.read();
  EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kPosition);
  EXPECT_EQ(robot.write(rig.torque(0.3)), phri::WriteStatus::kFault);
  EXPECT_TRUE(robot.state().stop_requested);
  std::rewind(log);
  char text[512] = {};
  const std::string logged(text, std::fread(text, 1, sizeof text - 1, log));
  std::fclose(log);
  EXPECT_NE(logged.find("link degraded at t = "), std::string::npos) << logged;
  EXPECT_NE(logged.find("packet loss: 26 of the last 5000 Refresh failed, more than 0.5 %"), std::string::npos) << logged;
  EXPECT_EQ(std::count(logged.begin(), logged.end(), '\n'), 1);
}

TEST(KortexRobot, LossBudgetSettingsAreChecked) {
  Rig rig;
  phri::KortexRobotSettings s = gen3_like();
  s.max_loss_fraction = 1.0;
  EXPECT_THROW(rig.start(s), phri::ConfigError);
  s = gen3_like();
  s.loss_window_s = 0.0;
  EXPECT_THROW(rig.start(s), phri::ConfigError);
}

TEST(KortexRobot, DryRunNeverLeavesPosition) {
  Rig rig;
  phri::KortexRobotSettings settings = gen3_like();
  settings.dry_run = true;
  KortexRobot& robot = rig.start(settings);
  for (int k = 0; k < 20; ++k) {
    robot.read();
    EXPECT_EQ(robot.write(rig.torque(5.0)), phri::WriteStatus::kOk);
  }
  robot.read();
  EXPECT_EQ(rig.arm.control_mode(0), kortex::ControlMode::kPosition);
  EXPECT_EQ(robot.command().actuators[0].torque_joint_Nm, 0.0f);
  EXPECT_LT((rig.plant.true_q() - start_pose()).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(KortexRobot, CycleAllocatesNothingThroughModeSwitches) {
  Rig rig;
  KortexRobot& robot = rig.start();
  phri::RobotCommand torque = rig.torque(0.1), current(7), position(7);
  current.mode = phri::LowLevelMode::kCurrent;
  robot.read();
  position.q_rad = robot.state().q_rad;
  phri::test::AllocationCounter count;
  for (int k = 0; k < 300; ++k) {
    robot.read();
    robot.write(k < 100 ? torque : k < 200 ? current : position);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(robot.health().mode_switches, 3u);
}

// ---------------------------------------------------------------------------- start-up refusals

// Forwards to the emulator but reports a chosen arm state in the first feedback.
class WrongStateClient final : public phri::KortexClient {
public:
  explicit WrongStateClient(KortexEmulator& arm) : arm_(arm) {}
  kortex::CallStatus create_sessions(const kortex::SessionSettings& s) override { return arm_.create_sessions(s); }
  kortex::CallStatus close_sessions() override { return arm_.close_sessions(); }
  kortex::CallStatus actuator_count(int& n) override { return arm_.actuator_count(n); }
  kortex::CallStatus arm_state(kortex::ArmState& s) override { return arm_.arm_state(s); }
  kortex::CallStatus servoing_mode(kortex::ServoingMode& m) override { return arm_.servoing_mode(m); }
  kortex::CallStatus set_servoing_mode(kortex::ServoingMode m) override { return arm_.set_servoing_mode(m); }
  kortex::CallStatus clear_faults() override { return arm_.clear_faults(); }
  kortex::CallStatus stop() override { return arm_.stop(); }
  kortex::CallStatus apply_emergency_stop() override { return arm_.apply_emergency_stop(); }
  kortex::CallStatus set_control_mode(int i, kortex::ControlMode m) override { return arm_.set_control_mode(i, m); }
  kortex::CallStatus refresh(const kortex::CyclicCommand& c, kortex::CyclicFeedback& f) noexcept override { return arm_.refresh(c, f); }
  kortex::CallStatus refresh_feedback(kortex::CyclicFeedback& f) noexcept override {
    const kortex::CallStatus s = arm_.refresh_feedback(f);
    f.base.active_state = kortex::ArmState::kServoingReady;  // e.g. another client took the arm
    return s;
  }
  double clock_s() const noexcept override { return arm_.clock_s(); }
  std::string describe() const override { return "kortex test"; }

private:
  KortexEmulator& arm_;
};

void expect_one_line_refusal(const std::function<void()>& start, const std::string& fragment) {
  try {
    start();
    ADD_FAILURE() << "no refusal, expected: " << fragment;
  } catch (const phri::HardwareError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(KortexRobot, StartUpRefusalsSayWhyInOneLineAndPutTheArmBack) {
  {
    Rig rig;
    rig.arm.set_reported_actuator_count(6);
    expect_one_line_refusal([&] { rig.start(); }, "kortex emulator: the arm reports 6 actuators, the robot has 7 joints");
    EXPECT_FALSE(rig.arm.sessions_open());
  }
  {
    Rig rig;
    rig.arm.create_sessions({});
    rig.arm.inject_fault(1, kortex::safety_bit::kJointLimitHigh);
    expect_one_line_refusal([&] { rig.start(); }, "the arm is in fault (ARMSTATE_IN_FAULT)");
  }
  {
    Eigen::VectorXd q = start_pose();
    q[3] = -2.7;  // joint 4 beyond its -2.57 rad
    Rig rig(q);
    expect_one_line_refusal([&] { rig.start(); }, "joint 4 at -154.7 deg is outside its limits [-147.3, 147.3] deg");
    EXPECT_EQ(rig.arm.servoing(), kortex::ServoingMode::kSingleLevel);  // put back
    EXPECT_FALSE(rig.arm.sessions_open());
  }
  {
    Rig rig;
    WrongStateClient client(rig.arm);
    expect_one_line_refusal([&] { KortexRobot robot(client, gen3_like()); },
                            "after LOW_LEVEL_SERVOING the arm reports ARMSTATE_SERVOING_READY, not ARMSTATE_SERVOING_LOW_LEVEL");
    EXPECT_EQ(rig.arm.servoing(), kortex::ServoingMode::kSingleLevel);
  }
  {
    Rig rig;
    phri::KortexRobotSettings settings = gen3_like();
    settings.torque_per_amp_Nm_per_A.resize(3);
    EXPECT_THROW(rig.start(settings), phri::ConfigError);
  }
}

}  // namespace
