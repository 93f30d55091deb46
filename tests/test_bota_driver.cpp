// ctest-labels: integration
// The SensONE driver (hardware/bota_sens_one.hpp) end to end through a pseudo-terminal, against the
// fake sensor (hardware/bota_emulator.hpp):
//   the handshake ('C', 'c,...', 'f,...', 'R' with their acks), from a sensor still streaming and
//   from one booting ("App Init"); a steady stream (every frame, values bit-exact, consecutive
//   timestamps, the rate); each injected fault with its exact counters, and no published wrench
//   ever anything but a good frame that was sent; stalls (stale, then fresh again), silence
//   (reconnection), disconnect (invalid, then recovery on the new pty); a refused configuration;
//   open errors that name the device and the remedy; bounded shutdown; a consumer that allocates
//   nothing. Timeouts are generous (2 shared cores): the tests wait for conditions, never for time.
#include <phri/core/error.hpp>
#include <phri/hardware/bota_emulator.hpp>
#include <phri/hardware/bota_sens_one.hpp>
#include <phri/hardware/serial_port.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace {

using namespace std::chrono_literals;
using phri::BotaEmulator;
using phri::BotaEmulatorSettings;
using phri::BotaFault;
using phri::BotaSensOne;
using phri::BotaSensOneSettings;
using phri::WrenchSample;
using Clock = std::chrono::steady_clock;

bool wait_for(const std::function<bool()>& condition, double timeout_s = 4.0) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(1ms);
  }
  return condition();
}

BotaSensOneSettings driver_settings(const std::string& device) {
  BotaSensOneSettings s;
  s.device = device;
  s.history_capacity = 1 << 16;
  s.reconnect_after_silence_s = 3.0;  // pauses of the stream in these tests are not silences
  s.retry_initial_s = 0.02;
  s.retry_max_s = 0.2;
  return s;
}

struct History {
  std::size_t count = 0;
  WrenchSample first, last;
};

// Every sample the driver published since the last call is a good frame the emulator sent
// (bit-exact), in order, with sequence numbers +1 each.
History check_history(BotaSensOne& driver, const BotaEmulator& emulator, std::uint32_t& last_sequence) {
  std::map<std::uint32_t, phri::BotaFrame> sent;
  for (const phri::BotaFrame& f : emulator.good_frames()) sent[f.timestamp] = f;
  History history;
  std::size_t& count = history.count;
  WrenchSample s;
  std::uint32_t last_timestamp = 0;
  while (driver.pop_history(s)) {
    if (count == 0) history.first = s;
    history.last = s;
    ++count;
    EXPECT_TRUE(s.valid);
    EXPECT_EQ(s.sequence, last_sequence + 1);
    last_sequence = s.sequence;
    const auto it = sent.find(s.sensor_timestamp);
    if (it == sent.end()) {
      ADD_FAILURE() << "published a frame that was never sent intact: timestamp " << s.sensor_timestamp;
      continue;
    }
    for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(s.wrench[i], static_cast<double>(it->second.wrench[i]));
    EXPECT_EQ(s.temperature, it->second.temperature);
    EXPECT_EQ(s.status, 0);
    EXPECT_GT(s.sensor_timestamp + (count == 1 ? 1u : 0u), last_timestamp);
    last_timestamp = s.sensor_timestamp;
  }
  return history;
}

class BotaDriver : public ::testing::Test {
protected:
  void start(BotaEmulatorSettings emulator_settings = {}, std::function<void(BotaSensOneSettings&)> tune = {}) {
    emulator_ = std::make_unique<BotaEmulator>(emulator_settings);
    BotaSensOneSettings s = driver_settings(emulator_->device());
    if (tune) tune(s);
    driver_ = std::make_unique<BotaSensOne>(s);
  }
  void wait_streaming() {
    ASSERT_TRUE(wait_for([&] { return driver_->counters().published >= 10; }))
        << "no stream; last error: " << driver_->last_error();
  }
  // Stream paused and every byte sent decoded: the two counts agree from here on.
  void quiesce() {
    emulator_->set_streaming(false);
    std::uint64_t bytes = driver_->counters().decoder.bytes;
    auto unchanged_since = Clock::now();
    while (Clock::now() - unchanged_since < 300ms) {
      std::this_thread::sleep_for(5ms);
      const std::uint64_t now = driver_->counters().decoder.bytes;
      if (now != bytes) {
        bytes = now;
        unchanged_since = Clock::now();
      }
    }
    base_driver_ = driver_->counters();
    base_emulator_ = emulator_->stats();
  }
  // Pauses the stream again and waits until the driver has decoded every byte sent since quiesce().
  void drain() {
    emulator_->set_streaming(false);
    ASSERT_TRUE(wait_for([&] {
      return driver_->counters().decoder.bytes - base_driver_.decoder.bytes ==
             emulator_->stats().stream_bytes - base_emulator_.stream_bytes;
    })) << "the driver did not decode every byte sent";
  }
  void inject_and_wait(BotaFault fault, int param, int good_frames_after = 5) {
    emulator_->inject(fault, param);
    ASSERT_TRUE(wait_for([&] { return emulator_->stats().faults_pending == 0; }));
    const std::uint64_t good = emulator_->stats().good_frames;
    ASSERT_TRUE(wait_for([&] { return emulator_->stats().good_frames >= good + static_cast<std::uint64_t>(good_frames_after); }));
  }

  std::unique_ptr<BotaEmulator> emulator_;
  std::unique_ptr<BotaSensOne> driver_;
  phri::BotaSensOneCounters base_driver_;
  phri::BotaEmulatorStats base_emulator_;
  std::uint32_t last_sequence_ = 0;
};

TEST_F(BotaDriver, HandshakesWithAStreamingSensorAndPublishesGoodFrames) {
  start();
  wait_streaming();
  EXPECT_EQ(emulator_->stats().run_mode_acks, 1u);
  EXPECT_EQ(driver_->counters().connections, 1u);
  EXPECT_TRUE(driver_->latest().connected);
  EXPECT_TRUE(driver_->latest().valid);
  EXPECT_EQ(driver_->last_error(), "");
  EXPECT_GE(check_history(*driver_, *emulator_, last_sequence_).count, 10u);
}

TEST_F(BotaDriver, HandshakesWithABootingSensorSayingAppInit) {
  BotaEmulatorSettings booting;
  booting.streaming_at_start = false;
  start(booting);
  wait_streaming();
  EXPECT_EQ(emulator_->stats().run_mode_acks, 1u);
  EXPECT_GE(check_history(*driver_, *emulator_, last_sequence_).count, 10u);
}

TEST_F(BotaDriver, SteadyStreamDeliversEveryFrameBitExactAtTheSensorRate) {
  BotaEmulatorSettings e;
  e.rate_hz = 500.0;
  start(e);
  wait_streaming();
  quiesce();
  check_history(*driver_, *emulator_, last_sequence_);
  emulator_->set_streaming(true);
  ASSERT_TRUE(wait_for([&] { return emulator_->stats().good_frames >= base_emulator_.good_frames + 500; }));
  drain();
  const auto now = driver_->counters();
  const auto sent = emulator_->stats().good_frames - base_emulator_.good_frames;
  EXPECT_EQ(now.decoder.frames_ok - base_driver_.decoder.frames_ok, sent);
  EXPECT_EQ(now.published - base_driver_.published, sent);
  // Values bit-exact, timestamps of consecutive slots, the rate as sent (loosely: a shared machine).
  const std::uint32_t sequence_before = last_sequence_;
  const History history = check_history(*driver_, *emulator_, last_sequence_);
  EXPECT_EQ(history.count, sent);
  EXPECT_EQ(history.last.sequence - sequence_before, sent);
  EXPECT_EQ(history.last.sensor_timestamp, BotaEmulator::expected_frame(emulator_->stats().slots - 1).timestamp);
  const double span_s = 1e-9 * static_cast<double>(history.last.host_stamp_ns - history.first.host_stamp_ns);
  const double rate_hz = static_cast<double>(history.count - 1) / span_s;
  EXPECT_GT(rate_hz, 250.0);
  EXPECT_LT(rate_hz, 1000.0);
  // No gap: the slots of the window are all there (timestamps are the slot numbers in base 128).
  EXPECT_EQ(emulator_->stats().slots - base_emulator_.slots, sent);
}

struct FaultCase {
  const char* name;
  BotaFault fault;
  int param;
  // expected change of the decoder's counters per occurrence (garbage: crc errors = its 0xAA bytes)
  std::uint64_t crc_errors, bytes_skipped, status_errors, invalid_values;
};

const FaultCase kFaultCases[] = {
    {"corrupt_crc", BotaFault::kCorruptCrc, 0, 1, 37, 0, 0},
    {"flipped_byte", BotaFault::kFlippedByte, 7, 1, 37, 0, 0},
    {"dropped_byte", BotaFault::kDroppedByte, 12, 1, 36, 0, 0},
    {"truncated", BotaFault::kTruncated, 20, 1, 20, 0, 0},
    {"garbage", BotaFault::kGarbage, 300, 0, 300, 0, 0},
    {"frame_burst", BotaFault::kFrameBurst, 40, 0, 0, 0, 0},
    {"nan", BotaFault::kNonFinite, 2, 0, 0, 0, 1},
    {"infinity", BotaFault::kNonFinite, 5, 0, 0, 0, 1},
    {"error_status", BotaFault::kErrorStatus, 3, 0, 0, 1, 0},
};

class BotaDriverFault : public BotaDriver, public ::testing::WithParamInterface<FaultCase> {};

TEST_P(BotaDriverFault, NoBogusWrenchIsPublishedAndTheCountersSayWhatHappened) {
  const FaultCase& c = GetParam();
  constexpr int kRepeats = 3;
  start();
  wait_streaming();
  quiesce();
  check_history(*driver_, *emulator_, last_sequence_);
  emulator_->set_streaming(true);
  for (int i = 0; i < kRepeats; ++i) inject_and_wait(c.fault, c.param);
  drain();
  const auto now = driver_->counters();
  const auto sent = emulator_->stats();
  const auto& d0 = base_driver_.decoder;
  const std::uint64_t garbage_headers = sent.garbage_headers - base_emulator_.garbage_headers;
  EXPECT_EQ(now.decoder.crc_errors - d0.crc_errors, kRepeats * c.crc_errors + garbage_headers);
  EXPECT_EQ(now.decoder.bytes_skipped - d0.bytes_skipped, kRepeats * c.bytes_skipped);
  EXPECT_EQ(now.decoder.resyncs - d0.resyncs, c.bytes_skipped > 0 ? kRepeats : 0u);
  EXPECT_EQ(now.decoder.status_errors - d0.status_errors, kRepeats * c.status_errors);
  EXPECT_EQ(now.decoder.invalid_values - d0.invalid_values, kRepeats * c.invalid_values);
  EXPECT_EQ(now.decoder.unconfirmed - d0.unconfirmed, 0u);
  // Every good frame sent got through, and nothing else.
  EXPECT_EQ(now.decoder.frames_ok - d0.frames_ok, sent.good_frames - base_emulator_.good_frames);
  EXPECT_EQ(check_history(*driver_, *emulator_, last_sequence_).count, sent.good_frames - base_emulator_.good_frames);
  EXPECT_EQ(now.connections, 1u);
  EXPECT_TRUE(driver_->latest().valid);
}

INSTANTIATE_TEST_SUITE_P(Faults, BotaDriverFault, ::testing::ValuesIn(kFaultCases),
                         [](const auto& info) { return std::string(info.param.name); });

TEST_F(BotaDriver, AStallMakesTheWrenchStaleThenFreshAgainWithoutReconnecting) {
  start();
  wait_streaming();
  phri::RobotState state(7);
  driver_->read_into(state);
  EXPECT_TRUE(state.wrench.valid);
  emulator_->inject(BotaFault::kStall, 600);
  ASSERT_TRUE(wait_for([&] {
    driver_->read_into(state);
    return !state.wrench.valid;
  })) << "the wrench never went stale";
  EXPECT_TRUE(driver_->latest().valid);  // the data are good, only old: the consumer sees its age
  const std::uint32_t stale_sequence = state.wrench.sequence;
  ASSERT_TRUE(wait_for([&] {
    driver_->read_into(state);
    return state.wrench.valid && state.wrench.sequence > stale_sequence;
  }));
  EXPECT_EQ(driver_->counters().connections, 1u);
  std::uint32_t sequence = 0;
  check_history(*driver_, *emulator_, sequence);
}

TEST_F(BotaDriver, ASilenceLongerThanTheLimitReconnectsAndTheStreamResumes) {
  start({}, [](BotaSensOneSettings& s) { s.reconnect_after_silence_s = 0.3; });
  wait_streaming();
  emulator_->set_streaming(false);
  ASSERT_TRUE(wait_for([&] { return driver_->counters().silences >= 1; }));
  emulator_->set_streaming(true);
  const auto published = driver_->counters().published;
  ASSERT_TRUE(wait_for([&] { return driver_->counters().published > published + 10 && driver_->latest().valid; }));
  EXPECT_GE(driver_->counters().connections, 2u);
  EXPECT_GE(emulator_->stats().run_mode_acks, 2u);
  std::uint32_t sequence = 0;
  check_history(*driver_, *emulator_, sequence);
}

TEST_F(BotaDriver, ADisconnectInvalidatesTheWrenchThenTheDriverRecoversOnTheNewDevice) {
  start();
  wait_streaming();
  emulator_->inject(BotaFault::kDisconnect, 400);
  phri::RobotState state(7);
  ASSERT_TRUE(wait_for([&] { return !driver_->latest().connected; })) << "the disconnect was not noticed";
  driver_->read_into(state);
  EXPECT_FALSE(state.wrench.valid);
  EXPECT_FALSE(driver_->latest().valid);
  ASSERT_TRUE(wait_for([&] { return driver_->latest().valid; })) << "no recovery; last error: " << driver_->last_error();
  driver_->read_into(state);
  EXPECT_TRUE(state.wrench.valid);
  const auto counters = driver_->counters();
  EXPECT_EQ(counters.connections, 2u);
  EXPECT_EQ(counters.disconnections, 1u);
  EXPECT_EQ(emulator_->stats().opens, 2u);
  EXPECT_EQ(emulator_->stats().run_mode_acks, 2u);
  std::uint32_t sequence = 0;
  check_history(*driver_, *emulator_, sequence);
}

TEST_F(BotaDriver, RepeatedDisconnectsAmidFaultsNeverCrashOrPublishABogusWrench) {
  start();
  wait_streaming();
  const BotaFault faults[] = {BotaFault::kGarbage, BotaFault::kDisconnect, BotaFault::kNonFinite, BotaFault::kTruncated,
                              BotaFault::kDisconnect, BotaFault::kErrorStatus, BotaFault::kDroppedByte};
  for (BotaFault f : faults) emulator_->inject(f, f == BotaFault::kDisconnect ? 50 : 17);
  ASSERT_TRUE(wait_for([&] { return emulator_->stats().faults_pending == 0; }));
  const auto published = driver_->counters().published;
  ASSERT_TRUE(wait_for([&] { return driver_->counters().published > published + 10 && driver_->latest().valid; }))
      << "no recovery; last error: " << driver_->last_error();
  EXPECT_EQ(driver_->counters().connections, 3u);
  std::uint32_t sequence = 0;
  check_history(*driver_, *emulator_, sequence);
}

TEST_F(BotaDriver, ARefusedConfigurationIsAHandshakeFailureAndNothingIsPublished) {
  BotaEmulatorSettings e;
  e.expected.sinc_length = 256;  // the fake sensor refuses our 'f,512,...'
  start(e, [](BotaSensOneSettings& s) { s.ack_timeout_s = 0.2; });
  ASSERT_TRUE(wait_for([&] { return driver_->counters().handshake_failures >= 2; }));
  EXPECT_EQ(driver_->counters().published, 0u);
  EXPECT_FALSE(driver_->latest().valid);
  const std::string error = driver_->last_error();
  EXPECT_NE(error.find("f,512,0,0,1"), std::string::npos) << error;
  EXPECT_NE(error.find("r,0,f,0"), std::string::npos) << error;
}

TEST(BotaSerialPort, OpenErrorsNameTheDeviceAndTheRemedy) {
  const std::string missing = "/nonexistent/ttyUSB7";
  try {
    phri::SerialPort port(missing, 460800);
    ADD_FAILURE() << "opened a missing device";
  } catch (const phri::IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("plugged"), std::string::npos) << e.what();
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("phri_serial_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string regular = (dir / "not_a_tty").string();
  std::ofstream(regular) << "x";
  try {
    phri::SerialPort port(regular, 460800);
    ADD_FAILURE() << "opened a regular file as a serial port";
  } catch (const phri::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("not a serial device"), std::string::npos) << e.what();
  }
  if (::geteuid() != 0) {  // root opens anything: the permission and exclusivity cases need an ordinary user
    BotaEmulator emulator;
    phri::SerialPort first(emulator.device(), 460800);
    try {
      phri::SerialPort second(emulator.device(), 460800);
      ADD_FAILURE() << "a second program could open the sensor";
    } catch (const phri::IoError& e) {
      EXPECT_NE(std::string(e.what()).find("another program"), std::string::npos) << e.what();
    }
    ::chmod(regular.c_str(), 0);
    try {
      phri::SerialPort port(regular, 460800);
      ADD_FAILURE() << "opened a file without permission";
    } catch (const phri::IoError& e) {
      EXPECT_NE(std::string(e.what()).find("dialout"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(BotaSensOne, AMissingDeviceIsRetriedAndReportedAndStopIsPrompt) {
  BotaSensOneSettings s = driver_settings("/nonexistent/ttyUSB7");
  BotaSensOne driver(s);
  ASSERT_TRUE(wait_for([&] { return driver.counters().open_failures >= 3; }));
  EXPECT_FALSE(driver.latest().valid);
  EXPECT_FALSE(driver.latest().connected);
  EXPECT_NE(driver.last_error().find("/nonexistent/ttyUSB7"), std::string::npos);
  const auto t0 = Clock::now();
  driver.stop();
  EXPECT_LT(Clock::now() - t0, 1s);
}

TEST_F(BotaDriver, StopIsPromptWhileStreamingAndWhileWaitingForAnAck) {
  start();
  wait_streaming();
  auto t0 = Clock::now();
  driver_->stop();
  EXPECT_LT(Clock::now() - t0, 1s);
  // A sensor that never answers: the driver is inside its ack wait.
  BotaEmulatorSettings mute;
  mute.expected.baud_config = 0;  // refuses our 'c'
  BotaEmulator emulator(mute);
  BotaSensOneSettings s = driver_settings(emulator.device());
  s.ack_timeout_s = 30.0;
  BotaSensOne waiting(s);
  ASSERT_TRUE(wait_for([&] { return emulator.stats().run_mode == false; }));
  std::this_thread::sleep_for(100ms);
  t0 = Clock::now();
  waiting.stop();
  EXPECT_LT(Clock::now() - t0, 1s);
}

TEST_F(BotaDriver, TheConsumerSideAllocatesNothing) {
  start();
  wait_streaming();
  phri::RobotState state(7);
  std::uint32_t newest = 0;
  phri::test::AllocationCounter count;
  for (int i = 0; i < 2000; ++i) {
    newest = std::max(newest, driver_->latest().sequence);
    driver_->read_into(state);
    std::this_thread::sleep_for(100us);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_GT(newest, 10u);
}

}  // namespace
