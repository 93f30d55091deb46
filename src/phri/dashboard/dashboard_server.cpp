#include <phri/dashboard/dashboard_server.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/dashboard/state_encoder.hpp>
#include <phri/model/collision_model.hpp>

#include <httplib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <functional>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string_view>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace phri {
namespace {

// The server's threads yield to the control loop: on a busy machine a page load or a hundred
// streams must not delay a cycle (Linux: a thread's nice value is its own).
constexpr int kServerNiceOffset = 10;

void lower_this_thread(int base_nice) {
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  ::setpriority(PRIO_PROCESS, tid, std::min(base_nice + kServerNiceOffset, 19));
}

// httplib's thread pool, each task run at the server's lower priority.
class NiceThreadPool final : public httplib::ThreadPool {
public:
  NiceThreadPool(std::size_t threads, int base_nice) : httplib::ThreadPool(threads), base_nice_(base_nice) {}
  void enqueue(std::function<void()> fn) override {
    httplib::ThreadPool::enqueue([fn = std::move(fn), base = base_nice_] {
      lower_this_thread(base);
      fn();
    });
  }

private:
  int base_nice_;
};

// The files the page may load, and only those: URL path -> file under the web root, MIME type.
struct StaticFile {
  std::string_view url, file, mime;
};
constexpr std::array<StaticFile, 8> kStaticFiles = {{
    {"/", "index.html", "text/html; charset=utf-8"},
    {"/favicon.svg", "favicon.svg", "image/svg+xml"},
    {"/app.js", "app.js", "text/javascript"},
    {"/style.css", "style.css", "text/css"},
    {"/vendor/three.module.js", "node_modules/three/build/three.module.js", "text/javascript"},
    {"/vendor/OrbitControls.js", "node_modules/three/examples/jsm/controls/OrbitControls.js", "text/javascript"},
    {"/vendor/uPlot.esm.js", "node_modules/uplot/dist/uPlot.esm.js", "text/javascript"},
    {"/vendor/uPlot.min.css", "node_modules/uplot/dist/uPlot.min.css", "text/css"},
}};

constexpr const char* kPing = ": ping\n\n";

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string error_json(const std::string& reason) {
  std::string escaped;
  for (char c : reason) {
    if (c == '"' || c == '\\') escaped += '\\';
    escaped += (static_cast<unsigned char>(c) < 0x20) ? ' ' : c;
  }
  return "{\"ok\":false,\"error\":\"" + escaped + "\"}";
}

// Equal strings, in a time that does not depend on where they differ.
bool same_token(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string cookie_token(const httplib::Request& req) {
  const std::string cookies = req.get_header_value("Cookie");
  const std::string key = "phri_token=";
  const std::size_t at = cookies.find(key);
  if (at == std::string::npos || (at > 0 && cookies[at - 1] != ' ' && cookies[at - 1] != ';')) return {};
  const std::size_t end = cookies.find(';', at);
  return cookies.substr(at + key.size(), end == std::string::npos ? std::string::npos : end - at - key.size());
}

}  // namespace

std::string random_token() {
  std::random_device device;
  std::string token;
  constexpr char kHex[] = "0123456789abcdef";
  for (int i = 0; i < 4; ++i) {
    std::uint32_t word = device();
    for (int k = 0; k < 8; ++k, word >>= 4) token += kHex[word & 0xf];
  }
  return token;
}

struct DashboardServer::Impl {
  Impl(LiveChannel& live, const Controller& controller, const DashboardSettings& s, const std::string& tok)
      : channel(live), settings(s), token(tok), collision(load_collision(controller)),
        encoder(controller.model(), collision ? &*collision : nullptr, encoder_settings(controller, s)),
        model_json(encoder.model_json()) {
    limits.bodies = controller.model().num_bodies();
    limits.max_push_N = s.push_max_N;
  }

  static std::optional<CollisionModel> load_collision(const Controller& controller) {
    return Controller::collision_model(controller.settings(), controller.model());
  }

  static StateEncoderSettings encoder_settings(const Controller& controller, const DashboardSettings& s) {
    StateEncoderSettings e;
    e.push_max_N = s.push_max_N;
    e.touch_threshold = controller.settings().compliance.touch_threshold;
    e.release_threshold = controller.settings().compliance.release_threshold;
    e.end_effector_frame = controller.settings().end_effector_frame;
    e.body_regions = s.body_regions;
    return e;
  }

  bool authorised(const httplib::Request& req) const {
    if (req.has_param("token")) return same_token(req.get_param_value("token"), token);
    if (req.has_header("X-Phri-Token")) return same_token(req.get_header_value("X-Phri-Token"), token);
    return same_token(cookie_token(req), token);
  }

  void refuse(httplib::Response& res, int status, const std::string& reason) {
    ++refused;
    res.status = status;
    res.set_content(error_json(reason), "application/json");
  }

  void routes();
  void serve_static(const StaticFile& file, const httplib::Request& req, httplib::Response& res);
  void serve_stream(httplib::Response& res);
  void serve_log(httplib::Response& res);
  void serve_command(const httplib::Request& req, httplib::Response& res);
  void pump();
  void stop();

  LiveChannel& channel;
  DashboardSettings settings;
  std::string token;
  DashboardRequestLimits limits;
  std::optional<CollisionModel> collision;
  StateEncoder encoder;
  std::string model_json;
  httplib::Server server;
  std::thread listener, pumper;

  // The latest frame, shared by every stream (a slow client skips frames, it never queues them).
  std::mutex mutex;
  std::condition_variable changed;
  std::shared_ptr<const std::string> frame = std::make_shared<const std::string>(kPing);
  std::uint64_t sequence = 0;
  bool stopping = false;

  std::atomic<std::uint64_t> frames{0}, streams_opened{0}, commands{0}, refused{0};
  std::atomic<int> streams_open{0};
  std::atomic<double> last_time_s{-1.0};
  std::atomic<bool> last_paused{false};
};

void DashboardServer::Impl::routes() {
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (authorised(req)) return httplib::Server::HandlerResponse::Unhandled;
    refuse(res, 401, "missing or wrong token: open the address phri printed at start");
    return httplib::Server::HandlerResponse::Handled;
  });
  for (const StaticFile& file : kStaticFiles) {
    server.Get(std::string(file.url), [this, &file](const httplib::Request& req, httplib::Response& res) {
      serve_static(file, req, res);
    });
  }
  server.Get("/api/model", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(model_json, "application/json");
  });
  server.Get("/api/status", [this](const httplib::Request&, httplib::Response& res) {
    std::ostringstream s;
    s << "{\"frames\":" << frames << ",\"streams_open\":" << streams_open << ",\"streams_opened\":" << streams_opened
      << ",\"commands\":" << commands << ",\"refused\":" << refused << ",\"snapshots_dropped\":" << channel.dropped()
      << ",\"time_s\":" << last_time_s << ",\"paused\":" << (last_paused ? "true" : "false") << "}";
    res.set_content(s.str(), "application/json");
  });
  server.Get("/api/stream", [this](const httplib::Request&, httplib::Response& res) { serve_stream(res); });
  server.Get("/api/log", [this](const httplib::Request&, httplib::Response& res) { serve_log(res); });
  server.Post(R"(/api/([a-z]+))", [this](const httplib::Request& req, httplib::Response& res) { serve_command(req, res); });
  server.set_error_handler([this](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 413) {
      ++refused;
      res.set_content(error_json("body too large: at most " + std::to_string(limits.max_body_bytes) + " bytes"),
                      "application/json");
    } else if (res.status == 404) {
      res.set_content(error_json("not found"), "application/json");
    }
  });
}

void DashboardServer::Impl::serve_static(const StaticFile& file, const httplib::Request& req, httplib::Response& res) {
  const std::string body = read_file(std::filesystem::path(settings.web_root) / file.file);
  if (body.empty()) {
    res.status = 404;
    res.set_content(error_json(std::string(file.file) + " is missing: run scripts/setup (npm packages)"), "application/json");
    return;
  }
  // The page's later requests (scripts, stream, POSTs) carry the token as a same-site cookie.
  if (file.url == "/" && req.has_param("token")) {
    res.set_header("Set-Cookie", "phri_token=" + token + "; Path=/; HttpOnly; SameSite=Strict");
  }
  res.set_header("Cache-Control", "no-store");
  res.set_content(body, std::string(file.mime));
}

void DashboardServer::Impl::serve_stream(httplib::Response& res) {
  if (streams_open.fetch_add(1) >= settings.max_streams) {
    streams_open.fetch_sub(1);
    refuse(res, 503, "too many streams open (" + std::to_string(settings.max_streams) + ")");
    --refused;  // busy, not a bad request
    return;
  }
  ++streams_opened;
  res.set_header("Cache-Control", "no-store");
  auto seen = std::make_shared<std::uint64_t>(0);
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, seen](std::size_t, httplib::DataSink& sink) {
        std::shared_ptr<const std::string> next;
        {
          std::unique_lock<std::mutex> lock(mutex);
          changed.wait_for(lock, std::chrono::seconds(1), [&] { return stopping || sequence != *seen; });
          if (stopping) return false;
          next = sequence != *seen ? frame : nullptr;
          *seen = sequence;
        }
        // Idle (paused, or no loop yet): a comment line, which also finds clients that left.
        if (!next) return sink.write(kPing, std::char_traits<char>::length(kPing));
        return sink.write(next->data(), next->size());
      },
      [this](bool) { streams_open.fetch_sub(1); });
}

void DashboardServer::Impl::serve_log(httplib::Response& res) {
  std::error_code ec;
  const auto size = settings.log_path.empty() ? 0 : std::filesystem::file_size(settings.log_path, ec);
  if (settings.log_path.empty() || ec) {
    res.status = 404;
    res.set_content(error_json(settings.log_path.empty() ? "this run keeps no log" : "the log is not there yet"),
                    "application/json");
    return;
  }
  // The writer thread flushes every few milliseconds (an MCAP log: a chunk at least every second):
  // the file up to now, sent in pieces (a long run's log is hundreds of MB; it is never held in memory
  // whole). An MCAP log taken mid-run has no summary yet: `phri log export` reads it to its last chunk.
  res.set_header("Content-Disposition", "attachment; filename=\"" +
                                            std::filesystem::path(settings.log_path).filename().string() + "\"");
  auto file = std::make_shared<std::ifstream>(settings.log_path, std::ios::binary);
  const bool mcap = std::filesystem::path(settings.log_path).extension() == ".mcap";
  res.set_content_provider(static_cast<std::size_t>(size), mcap ? "application/octet-stream" : "text/csv",
                           [file](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             std::array<char, 65536> buffer;
                             file->seekg(static_cast<std::streamoff>(offset));
                             file->read(buffer.data(), static_cast<std::streamsize>(std::min(length, buffer.size())));
                             const auto got = static_cast<std::size_t>(file->gcount());
                             return got > 0 && sink.write(buffer.data(), got);
                           });
}

void DashboardServer::Impl::serve_command(const httplib::Request& req, httplib::Response& res) {
  const DashboardRequest parsed = parse_dashboard_request(req.matches[1].str(), req.body, limits);
  if (!parsed.command) {
    refuse(res, parsed.status, parsed.error);
    return;
  }
  if (!channel.send(*parsed.command)) {
    res.status = 503;
    res.set_content(error_json("the loop is not taking commands (queue full)"), "application/json");
    return;
  }
  ++commands;
  std::ostringstream reply;
  reply << "{\"ok\":true";
  if (parsed.command->kind == LiveCommand::Kind::kPush) reply << ",\"applied_N\":" << parsed.push_applied_N;
  // Stepping a running loop pauses it first: the answer says so rather than a bare ok.
  if (parsed.command->kind == LiveCommand::Kind::kStep && !last_paused) reply << ",\"note\":\"the run was paused to step\"";
  reply << "}";
  res.set_content(reply.str(), "application/json");
}

// Encodes the newest snapshot at most frame_rate_hz times a second (older ones are skipped:
// the plots want the present, the log keeps every cycle).
void DashboardServer::Impl::pump() {
  const auto period = std::chrono::duration<double>(1.0 / settings.frame_rate_hz);
  LiveSnapshot snapshot;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex);
      if (changed.wait_for(lock, period, [&] { return stopping; })) return;
    }
    bool fresh = false;
    while (channel.next_snapshot(snapshot)) fresh = true;
    if (!fresh) continue;
    last_time_s = snapshot.row.time_s;
    last_paused = snapshot.paused;
    auto text = std::make_shared<const std::string>("data: " + encoder.frame_json(snapshot) + "\n\n");
    {
      const std::lock_guard<std::mutex> lock(mutex);
      frame = std::move(text);
      ++sequence;
    }
    ++frames;
    changed.notify_all();
  }
}

void DashboardServer::Impl::stop() {
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (stopping) return;
    stopping = true;
  }
  changed.notify_all();
  server.stop();
  if (listener.joinable()) listener.join();
  if (pumper.joinable()) pumper.join();
}

DashboardServer::DashboardServer(LiveChannel& channel, const Controller& controller, const DashboardSettings& settings)
    : token_(settings.token.empty() ? random_token() : settings.token) {
  if (!std::filesystem::exists(std::filesystem::path(settings.web_root) / "index.html")) {
    throw ConfigError(settings.web_root, "web_root", "no index.html there (the dashboard's page, web/)");
  }
  if (!(settings.push_max_N > 0.0) || !(settings.frame_rate_hz > 0.0) || settings.max_streams < 1) {
    throw ConfigError("dashboard", "settings", "push_max_N, frame_rate_hz and max_streams must be positive");
  }
  std::signal(SIGPIPE, SIG_IGN);  // a client that leaves mid-write is an error code, not a signal
  impl_ = std::make_unique<Impl>(channel, controller, settings, token_);
  Impl& s = *impl_;
  s.server.set_payload_max_length(s.limits.max_body_bytes);
  s.server.set_keep_alive_timeout(2);
  s.server.set_tcp_nodelay(true);  // a frame goes out when written (Nagle would batch the stream's small writes)
  // One thread per open stream plus a few for the page's requests.
  const std::size_t threads = static_cast<std::size_t>(settings.max_streams) + 8;
  errno = 0;
  const int base_nice = ::getpriority(PRIO_PROCESS, 0);
  s.server.new_task_queue = [threads, base_nice] { return new NiceThreadPool(threads, base_nice); };
  s.routes();
  port_ = settings.port == 0 ? s.server.bind_to_any_port(settings.bind_address)
                             : (s.server.bind_to_port(settings.bind_address, settings.port) ? settings.port : -1);
  if (port_ <= 0) {
    throw IoError(settings.bind_address + ":" + std::to_string(settings.port), "cannot listen there (in use, or no such address)");
  }
  s.listener = std::thread([&s, base_nice] {
    lower_this_thread(base_nice);
    s.server.listen_after_bind();
  });
  s.pumper = std::thread([&s, base_nice] {
    lower_this_thread(base_nice);
    s.pump();
  });
}

DashboardServer::~DashboardServer() { stop(); }

void DashboardServer::stop() {
  if (impl_) impl_->stop();
}

std::string DashboardServer::url() const {
  const std::string& host = impl_->settings.bind_address == "0.0.0.0" ? std::string("127.0.0.1") : impl_->settings.bind_address;
  return "http://" + host + ":" + std::to_string(port_) + "/?token=" + token_;
}

DashboardStats DashboardServer::stats() const {
  DashboardStats s;
  s.frames = impl_->frames;
  s.streams_opened = impl_->streams_opened;
  s.streams_open = impl_->streams_open;
  s.commands = impl_->commands;
  s.refused = impl_->refused;
  s.time_s = impl_->last_time_s;
  s.paused = impl_->last_paused;
  return s;
}

}  // namespace phri
