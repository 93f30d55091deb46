#include <phri/hardware/bota_sens_one.hpp>

#include <phri/core/error.hpp>
#include <phri/hardware/serial_port.hpp>

#include <algorithm>

namespace phri {
namespace {

constexpr int kPollSliceMs = 20;     // how often the thread looks at the stop flag while waiting
constexpr int kWriteTimeoutMs = 100;
constexpr std::size_t kReadChunk = 4096;
constexpr std::size_t kAckWindow = 4096;  // bytes of unanswered chatter kept while looking for an ack

std::int64_t to_ns(BotaSensOne::Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

}  // namespace

BotaSensOne::BotaSensOne(BotaSensOneSettings settings)
    : settings_(std::move(settings)), decoder_(settings_.decoder) {
  if (settings_.history_capacity > 0) history_ = std::make_unique<SpscRing<WrenchSample>>(settings_.history_capacity);
  thread_ = std::thread([this] { run(); });
}

BotaSensOne::~BotaSensOne() { stop(); }

void BotaSensOne::stop() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stopping_.store(true, std::memory_order_relaxed);
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void BotaSensOne::read_into(RobotState& state) noexcept {
  const WrenchSample& sample = handoff_.latest();
  const std::int64_t now_ns = to_ns(Clock::now());
  for (int i = 0; i < 6; ++i) state.wrench_sensor[i] = sample.wrench[static_cast<std::size_t>(i)];
  state.wrench.valid = sample.valid && sample.age_s(now_ns) <= settings_.stale_after_s;
  state.wrench.sequence = sample.sequence;
  state.wrench.stamp_s = 1e-9 * static_cast<double>(sample.host_stamp_ns);
}

BotaSensOneCounters BotaSensOne::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

std::string BotaSensOne::last_error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

void BotaSensOne::note(const std::string& error) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_error_ = error;
}

void BotaSensOne::update_counters() {
  thread_counters_.decoder = decoder_.counters();
  std::lock_guard<std::mutex> lock(mutex_);
  counters_ = thread_counters_;
}

// ---------------------------------------------------------------------------- reader thread

void BotaSensOne::run() {
  double backoff_s = settings_.retry_initial_s;
  while (!stopping()) {
    std::unique_ptr<SerialPort> port;
    if (!connect(port)) {
      update_counters();
      wait_before_retry(backoff_s);
      backoff_s = std::min(2.0 * backoff_s, settings_.retry_max_s);
      continue;
    }
    backoff_s = settings_.retry_initial_s;
    stream(*port);
    publish_link(false);
    if (!stopping()) ++thread_counters_.disconnections;
    update_counters();
  }
}

bool BotaSensOne::connect(std::unique_ptr<SerialPort>& port) {
  try {
    port = std::make_unique<SerialPort>(settings_.device, kBotaBaudRate);
  } catch (const Error& e) {
    ++thread_counters_.open_failures;
    note(e.what());
    return false;
  }
  if (!handshake(*port)) {
    if (!stopping()) ++thread_counters_.handshake_failures;
    return false;
  }
  ++thread_counters_.connections;
  note("");
  return true;
}

// The start-up sequence of Bota's example: config mode, communication, filter, run mode. A sensor
// left streaming by an earlier session answers 'C' too: the ack is looked for amid its frames.
bool BotaSensOne::handshake(SerialPort& port) {
  bool in_config_mode = false;
  for (int attempt = 0; attempt < std::max(1, settings_.config_mode_attempts) && !in_config_mode; ++attempt) {
    if (stopping()) return false;
    in_config_mode = command(port, kBotaConfigModeCommand, 'C');
  }
  return in_config_mode && command(port, bota_communication_command(settings_.sensor), 'c') &&
         command(port, bota_filter_command(settings_.sensor), 'f') && command(port, kBotaRunModeCommand, 'R');
}

// Sends `text` and reads until its acknowledgement; the bytes after the ack stay in after_ack_.
bool BotaSensOne::command(SerialPort& port, const std::string& text, char ack_letter) {
  const std::string ack = bota_ack(ack_letter);
  const std::string what = settings_.device + ": command '" + text + "': ";
  if (port.write_all(text, kWriteTimeoutMs).status != SerialStatus::kData) {
    note(what + "cannot write to the device");
    return false;
  }
  const auto deadline = Clock::now() + std::chrono::duration<double>(settings_.ack_timeout_s);
  std::string received;
  std::array<std::uint8_t, kReadChunk> chunk{};
  while (!stopping() && Clock::now() < deadline) {
    const SerialResult r = port.read_some(chunk.data(), chunk.size(), kPollSliceMs);
    if (r.status == SerialStatus::kClosed) {
      note(what + "the device closed before acknowledging");
      return false;
    }
    received.append(reinterpret_cast<const char*>(chunk.data()), r.bytes);
    const std::size_t at = received.find(ack);
    if (at != std::string::npos) {
      after_ack_ = received.substr(at + ack.size());
      return true;
    }
    if (received.size() > kAckWindow) received.erase(0, received.size() - ack.size());
  }
  note(what + "no acknowledgement '" + ack + "' within " + std::to_string(settings_.ack_timeout_s) + " s");
  return false;
}

void BotaSensOne::stream(SerialPort& port) {
  decoder_.reset();
  publish_link(true);
  Clock::time_point last_good = Clock::now();
  feed(reinterpret_cast<const std::uint8_t*>(after_ack_.data()), after_ack_.size(), last_good, last_good);
  after_ack_.clear();
  std::array<std::uint8_t, kReadChunk> chunk{};
  const auto silence = std::chrono::duration<double>(settings_.reconnect_after_silence_s);
  while (!stopping()) {
    const SerialResult r = port.read_some(chunk.data(), chunk.size(), kPollSliceMs);
    const Clock::time_point now = Clock::now();
    if (r.status == SerialStatus::kClosed) {
      note(settings_.device + ": the device closed (hang-up, end of file or I/O error" +
           (r.error != 0 ? std::string(": errno ") + std::to_string(r.error) : std::string()) + ")");
      return;
    }
    feed(chunk.data(), r.bytes, now, last_good);
    update_counters();
    if (now - last_good > silence) {
      ++thread_counters_.silences;
      note(settings_.device + ": no good frame for " + std::to_string(settings_.reconnect_after_silence_s) + " s");
      return;
    }
  }
}

void BotaSensOne::feed(const std::uint8_t* bytes, std::size_t count, Clock::time_point received,
                       Clock::time_point& last_good) {
  for (std::size_t i = 0; i < count; ++i) {
    if (decoder_.push(bytes[i])) {
      publish_frame(decoder_.frame(), received);
      last_good = received;
    }
  }
}

void BotaSensOne::publish_frame(const BotaFrame& frame, Clock::time_point received) {
  WrenchSample& s = last_published_;
  for (std::size_t i = 0; i < 6; ++i) s.wrench[i] = frame.wrench[i];
  s.valid = true;
  s.connected = true;
  ++s.sequence;
  s.host_stamp_ns = to_ns(received);
  s.sensor_timestamp = frame.timestamp;
  s.temperature = frame.temperature;
  s.status = frame.status;
  handoff_.publish(s);
  ++thread_counters_.published;
  if (history_ && !history_->try_push(s)) ++thread_counters_.history_dropped;
}

// A change of the link: the last good values stay, marked not valid until a new frame arrives.
void BotaSensOne::publish_link(bool connected) {
  last_published_.valid = false;
  last_published_.connected = connected;
  handoff_.publish(last_published_);
}

void BotaSensOne::wait_before_retry(double seconds) {
  std::unique_lock<std::mutex> lock(wake_mutex_);
  wake_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return stopping(); });
}

}  // namespace phri
