// ctest-labels: unit
// phri::KortexSdkClient, the adapter to Kinova's Kortex C++ API, compiled against the SDK-shaped
// test double (tests/kortex_sdk_double/: the documented classes, calls and accessors, an
// in-memory arm that records every call): connection and sessions on TCP 10000 / UDP 10001, the
// mode calls routed to device id index + 1, the cyclic messages field by field, SDK exceptions
// and timeouts as CallStatus, the teardown order, and KortexRobot's whole sequence through it.
#include <phri/hardware/kortex_robot.hpp>
#include <phri/hardware/kortex_sdk/kortex_sdk_client.hpp>

#include <kortex_sdk_double.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace {

namespace kortex = phri::kortex;

std::vector<std::string> all_devices(const std::string& mode) {
  std::vector<std::string> out;
  for (int i = 1; i <= 7; ++i) out.push_back("SetControlMode device " + std::to_string(i) + " " + mode);
  return out;
}

std::vector<std::string> join(std::vector<std::vector<std::string>> parts) {
  std::vector<std::string> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

phri::KortexRobotSettings seven_joints() {
  phri::KortexRobotSettings s;
  s.dof = 7;
  s.torque_per_amp_Nm_per_A = Eigen::VectorXd::Constant(7, 11.0);
  s.log = nullptr;
  return s;
}

TEST(KortexSdkClient, ConnectsBothTransportsAndOpensTwoSessions) {
  kortex_sdk_double::reset();
  {
    phri::KortexSdkSettings settings;
    settings.ip = "10.0.0.2";
    phri::KortexSdkClient client(settings);
    EXPECT_EQ(client.describe(), "kortex 10.0.0.2");
    kortex::SessionSettings session;
    session.session_inactivity_timeout_ms = 6000;
    ASSERT_TRUE(client.create_sessions(session).ok());
    EXPECT_EQ(kortex_sdk_double::arm().sessions, 2);
  }
  const std::vector<std::string> expected{"TCP connect 10.0.0.2:10000", "UDP connect 10.0.0.2:10001",
                                          "CreateSession admin 6000 2000", "CreateSession admin 6000 2000",
                                          "CloseSession", "CloseSession", "SetActivationStatus false",
                                          "SetActivationStatus false", "TCP disconnect", "UDP disconnect"};
  EXPECT_EQ(kortex_sdk_double::arm().calls, expected);
  EXPECT_EQ(kortex_sdk_double::arm().sessions, 0);
}

TEST(KortexSdkClient, UnreachableArmIsOneLine) {
  kortex_sdk_double::reset();
  kortex_sdk_double::arm().reachable = false;
  try {
    phri::KortexSdkClient client;
    ADD_FAILURE() << "no error";
  } catch (const phri::HardwareError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("kortex 192.168.1.10: no answer on TCP 10000"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(KortexSdkClient, ExceptionsAndTimeoutsBecomeStatuses) {
  kortex_sdk_double::reset();
  phri::KortexSdkClient client;
  kortex::CyclicCommand command;
  command.actuators.resize(7);
  kortex::CyclicFeedback feedback;
  feedback.actuators.resize(7);
  // no session yet
  kortex::CallStatus s = client.refresh(command, feedback);
  EXPECT_EQ(s.code, kortex::ErrorCode::kDevice);
  EXPECT_EQ(s.sub_code, kortex::sub_error::kInvalidSession);
  ASSERT_TRUE(client.create_sessions({}).ok());
  s = client.refresh(command, feedback);
  EXPECT_EQ(s.sub_code, kortex::sub_error::kWrongServoingMode);
  EXPECT_NE(client.last_error_text().find("ERROR_DEVICE"), std::string::npos) << client.last_error_text();
  ASSERT_TRUE(client.set_servoing_mode(kortex::ServoingMode::kLowLevel).ok());
  EXPECT_EQ(kortex_sdk_double::arm().servoing, Kinova::Api::Base::LOW_LEVEL_SERVOING);
  EXPECT_TRUE(client.refresh(command, feedback).ok());
  kortex_sdk_double::arm().time_out_next_refresh = true;
  s = client.refresh(command, feedback);
  EXPECT_EQ(s.sub_code, kortex::sub_error::kMethodTimeout);
  EXPECT_NE(client.last_error_text().find("timeout detected"), std::string::npos);
  kortex_sdk_double::arm().fail_next_config = Kinova::Api::ROBOT_IN_FAULT;
  EXPECT_EQ(client.set_control_mode(2, kortex::ControlMode::kTorque).sub_code, kortex::sub_error::kRobotInFault);
  EXPECT_EQ(client.set_control_mode(9, kortex::ControlMode::kTorque).sub_code, 52u);  // INVALID_DEVICE (device 10)
  // every Refresh with the cyclic timeout, never the SDK's 3 s default
  for (std::uint32_t t : kortex_sdk_double::arm().timeouts_ms) EXPECT_EQ(t, 3u);
  ASSERT_TRUE(client.apply_emergency_stop().ok());
  EXPECT_EQ(kortex_sdk_double::arm().calls.back(), "ApplyEmergencyStop timeout 100");
}

TEST(KortexSdkClient, CyclicMessagesFieldByField) {
  kortex_sdk_double::reset();
  phri::KortexSdkClient client;
  ASSERT_TRUE(client.create_sessions({}).ok());
  ASSERT_TRUE(client.set_servoing_mode(kortex::ServoingMode::kLowLevel).ok());
  ASSERT_TRUE(client.set_control_mode(1, kortex::ControlMode::kTorque).ok());
  kortex::CyclicCommand command;
  command.actuators.resize(7);
  command.frame_id = 65535;
  for (std::size_t i = 0; i < 7; ++i) {
    command.actuators[i] = {65535, 0, 12.5f + static_cast<float>(i), 0.0f, 1.5f * static_cast<float>(i), 0.25f};
  }
  kortex::CyclicFeedback feedback;
  feedback.actuators.resize(7);
  ASSERT_TRUE(client.refresh(command, feedback).ok());
  const Kinova::Api::BaseCyclic::Command& sent = kortex_sdk_double::arm().last_command;
  ASSERT_EQ(sent.actuators_size(), 7);
  EXPECT_EQ(sent.frame_id(), 65535u);
  EXPECT_EQ(sent.actuators(3).command_id(), 65535u);
  EXPECT_EQ(sent.actuators(3).position(), 15.5f);
  EXPECT_EQ(sent.actuators(3).torque_joint(), 4.5f);
  EXPECT_EQ(sent.actuators(3).current_motor(), 0.25f);
  EXPECT_EQ(feedback.frame_id, 65535u);
  EXPECT_EQ(feedback.base.active_state, kortex::ArmState::kServoingLowLevel);
  EXPECT_EQ(feedback.actuators[0].position_deg, 12.5f);  // POSITION actuator moved to its set-point
  EXPECT_EQ(feedback.actuators[1].position_deg, 10.0f);  // TORQUE actuator did not
  EXPECT_EQ(feedback.actuators[3].torque_Nm, -4.5f);     // reversed, as the arm reports it
  // a second Refresh reuses the message (no new actuator entries)
  command.frame_id = 0;
  ASSERT_TRUE(client.refresh(command, feedback).ok());
  EXPECT_EQ(kortex_sdk_double::arm().last_command.actuators_size(), 7);
}

TEST(KortexSdkClient, KortexRobotRunsItsWholeSequenceThroughTheAdapter) {
  kortex_sdk_double::reset();
  {
    phri::KortexSdkClient client;
    {
      phri::KortexRobot robot(client, seven_joints());
      robot.read();
      phri::RobotCommand c(7);
      c.mode = phri::LowLevelMode::kKinovaTorque;
      c.tau_Nm.setConstant(2.0);
      ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
      robot.read();
      ASSERT_EQ(robot.write(c), phri::WriteStatus::kOk);
      const phri::RobotState& s = robot.read();
      EXPECT_NEAR(s.tau_sensor_Nm[5], 2.0, 1e-6);   // sign flipped back
      EXPECT_NEAR(s.q_rad[0], 10.0 * std::numbers::pi / 180.0, 1e-6);
      EXPECT_EQ(kortex_sdk_double::arm().last_command.actuators(0).position(), 10.0f);  // echo
      EXPECT_FALSE(s.fault);
    }
  }
  const std::vector<std::string> expected = join({
      {"TCP connect 192.168.1.10:10000", "UDP connect 192.168.1.10:10001", "CreateSession admin 60000 2000",
       "CreateSession admin 60000 2000", "GetActuatorCount", "GetArmState", "SetServoingMode 2", "SetServoingMode 3",
       "RefreshFeedback"},
      all_devices("POSITION"),
      all_devices("TORQUE"),
      all_devices("POSITION"),
      {"SetServoingMode 2", "CloseSession", "CloseSession", "SetActivationStatus false", "SetActivationStatus false",
       "TCP disconnect", "UDP disconnect"},
  });
  EXPECT_EQ(kortex_sdk_double::arm().calls, expected);
}

}  // namespace
