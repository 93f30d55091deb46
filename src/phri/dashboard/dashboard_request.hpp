#pragma once
// phri::parse_dashboard_request: a POST of the dashboard's page (a JSON body) turned into one
// LiveCommand, or refused with a reason. Every check happens here, before anything reaches the
// loop: the body's size, JSON syntax, unknown or missing keys, names (events, gains), numbers
// that are not finite or out of their range. A push's force is capped at `max_push_N` (the
// reply says what was applied), not refused: dragging further only pushes as hard as allowed.
//
//   POST /api/event    {"event": "full_body_compliance"}          names: config/event.hpp
//   POST /api/gain     {"gain": "stiffness_scale", "value": 1.5}   names and ranges: app/live_gain.hpp
//   POST /api/push     {"body": 6, "point": [x, y, z], "force": [fx, fy, fz]}
//                      body: model body index; point: body frame [m], |point| <= 1; force: world [N]
//   POST /api/release  {}                                          ends the push
//   POST /api/run | /api/pause  {}
//   POST /api/step     {"cycles": n}      1 <= n <= 10000, default 1; pauses, runs n more cycles (steps add up)
#include <phri/app/live_channel.hpp>

#include <optional>
#include <string>
#include <string_view>

namespace phri {

struct DashboardRequestLimits {
  std::size_t max_body_bytes = 1024;
  int bodies = 7;            ///< model bodies a push may name
  double max_push_N = 100.0;
  int max_step_cycles = 10000;
};

struct DashboardRequest {
  std::optional<LiveCommand> command;  ///< empty: refused
  int status = 200;                    ///< HTTP status: 200, 400 (malformed, out of range), 404, 413
  std::string error;                   ///< why it was refused
  double push_applied_N = 0.0;         ///< a push: the magnitude after the cap
};

/// `action`: the path after /api/ ("event", "gain", ...).
DashboardRequest parse_dashboard_request(std::string_view action, std::string_view body,
                                         const DashboardRequestLimits& limits);

}  // namespace phri
