#include <phri/dashboard/dashboard_request.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

namespace phri {
namespace {

using nlohmann::json;

struct Refusal {
  int status;
  std::string reason;
};

// The object's keys must be among `allowed` (a typo is an error, as in the config files).
void only_keys(const json& j, std::initializer_list<std::string_view> allowed) {
  for (const auto& item : j.items()) {
    bool known = false;
    for (std::string_view a : allowed) known = known || item.key() == a;
    if (!known) throw Refusal{400, "unknown key '" + item.key() + "'"};
  }
}

const json& member(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end()) throw Refusal{400, std::string("missing key '") + key + "'"};
  return *it;
}

double finite_number(const json& j, const std::string& what) {
  if (!j.is_number()) throw Refusal{400, what + " must be a number"};
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw Refusal{400, what + " must be finite"};
  return v;
}

Eigen::Vector3d vector3(const json& j, const std::string& what) {
  if (!j.is_array() || j.size() != 3) throw Refusal{400, what + " must be an array of 3 numbers"};
  return {finite_number(j[0], what), finite_number(j[1], what), finite_number(j[2], what)};
}

std::string number_text(double v) {
  std::string s = std::to_string(v);
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

LiveCommand event_command(const json& j) {
  only_keys(j, {"event"});
  const json& name = member(j, "event");
  if (!name.is_string()) throw Refusal{400, "event must be a name"};
  const std::optional<Event> event = event_from_string(name.get<std::string>());
  if (!event) throw Refusal{400, "unknown event '" + name.get<std::string>() + "'"};
  LiveCommand c;
  c.kind = LiveCommand::Kind::kEvent;
  c.event = *event;
  return c;
}

LiveCommand gain_command(const json& j) {
  only_keys(j, {"gain", "value"});
  const json& name = member(j, "gain");
  if (!name.is_string()) throw Refusal{400, "gain must be a name"};
  const std::optional<LiveGain> gain = live_gain_from_string(name.get<std::string>());
  if (!gain) throw Refusal{400, "unknown gain '" + name.get<std::string>() + "'"};
  const double value = finite_number(member(j, "value"), "value");
  if (!in_range(*gain, value)) {
    const LiveGainRange r = range_of(*gain);
    throw Refusal{400, std::string(to_string(*gain)) + " must be within [" + number_text(r.min) + ", " +
                           number_text(r.max) + "]" + (r.mode_value ? " or -1 (the mode's)" : "") + ", got " +
                           number_text(value)};
  }
  LiveCommand c;
  c.kind = LiveCommand::Kind::kGain;
  c.gain = {*gain, value};
  return c;
}

LiveCommand push_command(const json& j, const DashboardRequestLimits& limits, double& applied) {
  only_keys(j, {"body", "point", "force"});
  const json& body = member(j, "body");
  if (!body.is_number_integer() || body.get<long>() < 0 || body.get<long>() >= limits.bodies) {
    throw Refusal{400, "body must be an integer in [0, " + std::to_string(limits.bodies - 1) + "]"};
  }
  LiveCommand c;
  c.kind = LiveCommand::Kind::kPush;
  c.push.body = body.get<int>();
  c.push.point_local = vector3(member(j, "point"), "point");
  if (c.push.point_local.norm() > 1.0) throw Refusal{400, "point must lie within 1 m of the body's origin"};
  c.push.force_world = vector3(member(j, "force"), "force");
  // Capped along its direction; the direction from the largest component first, so that a force
  // whose norm overflows (1e200 N) is capped, not zeroed.
  const double largest = c.push.force_world.cwiseAbs().maxCoeff();
  if (largest > 0.0) {
    const Eigen::Vector3d direction = (c.push.force_world / largest).normalized();
    const double magnitude = largest * (c.push.force_world / largest).norm();
    if (!(magnitude <= limits.max_push_N)) c.push.force_world = limits.max_push_N * direction;
  }
  applied = c.push.force_world.norm();
  return c;
}

LiveCommand step_command(const json& j, const DashboardRequestLimits& limits) {
  only_keys(j, {"cycles"});
  LiveCommand c;
  c.kind = LiveCommand::Kind::kStep;
  const auto it = j.find("cycles");
  if (it == j.end()) return c;
  if (!it->is_number_integer() || it->get<long>() < 1 || it->get<long>() > limits.max_step_cycles) {
    throw Refusal{400, "cycles must be an integer in [1, " + std::to_string(limits.max_step_cycles) + "]"};
  }
  c.steps = it->get<int>();
  return c;
}

LiveCommand bare_command(const json& j, LiveCommand::Kind kind) {
  only_keys(j, {});
  LiveCommand c;
  c.kind = kind;
  return c;
}

LiveCommand command_for(std::string_view action, const json& j, const DashboardRequestLimits& limits, double& applied) {
  if (action == "event") return event_command(j);
  if (action == "gain") return gain_command(j);
  if (action == "push") return push_command(j, limits, applied);
  if (action == "release") return bare_command(j, LiveCommand::Kind::kRelease);
  if (action == "run") return bare_command(j, LiveCommand::Kind::kRun);
  if (action == "pause") return bare_command(j, LiveCommand::Kind::kPause);
  if (action == "step") return step_command(j, limits);
  throw Refusal{404, "no action '" + std::string(action) + "'"};
}

// JSON with each object's keys given once: {"value": 3, "value": 1.5} is refused (nlohmann keeps the
// last one silently).
json parse_strict(std::string_view body) {
  std::vector<std::set<std::string>> keys;
  const json::parser_callback_t no_duplicates = [&keys](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keys.emplace_back();
    if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
    if (event == json::parse_event_t::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second) {
      throw Refusal{400, "key '" + parsed.get<std::string>() + "' given twice"};
    }
    return true;
  };
  return json::parse(body.begin(), body.end(), no_duplicates);
}

}  // namespace

DashboardRequest parse_dashboard_request(std::string_view action, std::string_view body,
                                         const DashboardRequestLimits& limits) {
  DashboardRequest out;
  try {
    if (body.size() > limits.max_body_bytes) {
      throw Refusal{413, "body of " + std::to_string(body.size()) + " bytes, at most " +
                             std::to_string(limits.max_body_bytes)};
    }
    // An empty body stands for {} (the bare actions).
    const json j = body.empty() ? json::object() : parse_strict(body);
    if (!j.is_object()) throw Refusal{400, "the body must be a JSON object"};
    out.command = command_for(action, j, limits, out.push_applied_N);
  } catch (const Refusal& r) {
    out.status = r.status;
    out.error = r.reason;
  } catch (const json::exception& e) {
    out.status = 400;
    out.error = std::string("malformed JSON: ") + e.what();
  }
  return out;
}

}  // namespace phri
