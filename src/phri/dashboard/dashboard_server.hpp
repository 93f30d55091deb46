#pragma once
// phri::DashboardServer: the live dashboard of `phri run --dashboard` (cpp-httplib, server-sent
// events). It serves the page (web/: index.html, app.js, style.css, and three.js and uPlot from
// web/node_modules, never a CDN), streams the loop's snapshots and turns the page's POSTs into
// LiveCommands. Everything runs on the server's own threads: the control thread only touches the
// LiveChannel (lock-free), so a slow, stalled or vanished client never delays a cycle.
//
//   phri::LiveChannel live;
//   phri::DashboardServer dashboard(live, controller, settings);   // binds; throws IoError
//   std::printf("%s\n", dashboard.url().c_str());                  // http://127.0.0.1:8080/?token=...
//   options.live = &live;  phri::run_session(robot, controller, fsm, ..., options, std::cout);
//
// Access: a random 128-bit token, required on every request (query ?token=, header X-Phri-Token
// or the cookie the page gets with its first load); without it 401 and nothing happens. The
// server listens on 127.0.0.1 unless told otherwise (bind_address; phri warns then).
//
// Endpoints (POST bodies and their checks: dashboard_request.hpp):
//   GET  /                   the page          GET /api/model   robot description (state_encoder.hpp)
//   GET  /api/stream         text/event-stream, one JSON frame per snapshot (~60 Hz), ": ping" when idle
//   GET  /api/log            the run's CSV log as written so far
//   GET  /api/status         server counters
//   POST /api/event | gain | push | release | run | pause | step
// The number of simultaneous streams is capped (max_streams, 503 beyond): each holds one thread.
#include <phri/app/live_channel.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/dashboard/dashboard_request.hpp>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace phri {

class Controller;

struct DashboardSettings {
  std::string bind_address = "127.0.0.1";
  int port = 8080;             ///< 0: any free port (port() tells which)
  std::string web_root;        ///< folder of index.html (and node_modules/ with three and uplot)
  std::string log_path;        ///< the run's CSV log; empty: /api/log answers 404
  double push_max_N = 100.0;   ///< drag-to-push force cap
  int max_streams = 32;        ///< simultaneous event streams
  double frame_rate_hz = 60.0; ///< most frames a second sent to the streams
  std::string token;           ///< empty: a random one
  /// The run's body regions (Config::body_regions): the page's power-and-force-limiting bars.
  std::optional<BodyRegionMap> body_regions;
};

struct DashboardStats {
  std::uint64_t frames = 0;           ///< frames encoded
  std::uint64_t streams_opened = 0;
  int streams_open = 0;
  std::uint64_t commands = 0;         ///< accepted and queued
  std::uint64_t refused = 0;          ///< 4xx answers (401 included)
  double time_s = -1.0;               ///< robot time of the newest snapshot encoded (-1: none yet)
  bool paused = false;                ///< ... and whether the loop was paused then
};

class DashboardServer {
public:
  /// Binds the socket and starts serving; throws IoError when the address cannot be bound,
  /// ConfigError when web_root has no index.html or the push cap is not positive.
  DashboardServer(LiveChannel& channel, const Controller& controller, const DashboardSettings& settings);
  ~DashboardServer();
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  /// Ends every stream, stops serving and joins the threads (idempotent).
  void stop();

  int port() const { return port_; }
  const std::string& token() const { return token_; }
  /// The page's address with its token.
  std::string url() const;
  DashboardStats stats() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
  std::string token_;
};

/// A random 128-bit token, 32 hex digits (std::random_device).
std::string random_token();

}  // namespace phri
