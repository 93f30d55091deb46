// ctest-labels: integration
// phri::DashboardServer and its request checks: real HTTP (cpp-httplib clients on 127.0.0.1)
// against a server on a free port.
//   - without the token (or with a wrong one) every address answers 401 and nothing reaches the loop;
//   - malformed, oversized, unknown and out-of-range requests are refused with a reason, nothing queued;
//   - a push is capped at the configured maximum, not refused;
//   - the page's events, gains and pushes reach the controller through the run loop's one path
//     (LiveChannel -> Fsm::post -> ControllerTargets), and the stream shows the result;
//   - 100 clients connecting and leaving while the loop runs in real time: all served, resident
//     memory does not grow, the loop keeps its pace (every snapshot handed over or dropped, none waited for).
#include <phri/config/config.hpp>
#include <phri/app/fsm.hpp>
#include <phri/app/live_channel.hpp>
#include <phri/app/run_session.hpp>
#include <phri/control/controller.hpp>
#include <phri/dashboard/dashboard_request.hpp>
#include <phri/dashboard/dashboard_server.hpp>
#include <phri/dashboard/state_encoder.hpp>
#include <phri/dashboard/stream_clients.hpp>
#include <phri/sim/sim_robot.hpp>

#include "allocation_counter.hpp"
#include "gen3_settings.hpp"

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <sstream>
#include <string>
#include <thread>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

phri::DashboardSettings local_settings() {
  phri::DashboardSettings s;
  s.port = 0;
  s.web_root = kRoot + "/web";
  return s;
}

int queued(phri::LiveChannel& channel) {
  int n = 0;
  for (phri::LiveCommand c; channel.receive(c);) ++n;
  return n;
}

// ---------------------------------------------------------------- request checks (no server)

// With body regions, the model lists each monitored link and the region it may meet, and each
// frame carries their v / v_max (the page's bars); without, neither.
TEST(DashboardEncoder, BodyRegionsGiveTheModelItsLinksAndEachFrameTheirRatios) {
  const phri::Controller cycle(phri::test::gen3_controller_settings());
  ASSERT_NE(cycle.collision(), nullptr);
  phri::StateEncoderSettings settings;
  settings.end_effector_frame = cycle.settings().end_effector_frame;
  phri::LiveSnapshot snapshot;
  snapshot.dof = 7;
  {
    phri::StateEncoder plain(cycle.model(), cycle.collision(), settings);
    EXPECT_TRUE(nlohmann::json::parse(plain.model_json())["contact"].empty());
    EXPECT_TRUE(nlohmann::json::parse(plain.frame_json(snapshot))["contact_ratio"].empty());
  }
  phri::BodyRegionMap regions;
  regions.region = {"lower_arm_wrist", 40000.0, 2.0, 160.0, 2.0};
  regions.links.emplace_back("end_effector_link", phri::BodyRegion{"hand_fingers", 75000.0, 0.6, 140.0, 2.0});
  settings.body_regions = regions;
  phri::StateEncoder encoder(cycle.model(), cycle.collision(), settings);
  const nlohmann::json contact = nlohmann::json::parse(encoder.model_json())["contact"];
  const std::vector<std::string> links = phri::PowerForceLimitMonitor::monitored_links(*cycle.collision());
  ASSERT_EQ(contact.size(), links.size());
  for (std::size_t i = 0; i < links.size(); ++i) {
    EXPECT_EQ(contact[i]["link"], links[i]);
    EXPECT_EQ(contact[i]["region"], links[i] == "end_effector_link" ? "hand_fingers" : "lower_arm_wrist");
  }
  snapshot.contact_links = static_cast<int>(links.size());
  for (int i = 0; i < snapshot.contact_links; ++i) snapshot.contact_ratio[static_cast<std::size_t>(i)] = 0.125 * i;
  const nlohmann::json ratio = nlohmann::json::parse(encoder.frame_json(snapshot))["contact_ratio"];
  ASSERT_EQ(ratio.size(), links.size());
  for (std::size_t i = 0; i < links.size(); ++i) EXPECT_EQ(ratio[i].get<double>(), 0.125 * static_cast<double>(i));
}

TEST(DashboardRequest, AcceptsEveryEventByNameAndRefusesUnknownOnes) {
  const phri::DashboardRequestLimits limits;
  for (std::string_view name : phri::kEventNames) {
    const auto r = phri::parse_dashboard_request("event", "{\"event\": \"" + std::string(name) + "\"}", limits);
    ASSERT_TRUE(r.command) << name << ": " << r.error;
    EXPECT_EQ(phri::to_string(r.command->event), name);
  }
  const auto bad = phri::parse_dashboard_request("event", R"({"event": "fly"})", limits);
  EXPECT_FALSE(bad.command);
  EXPECT_EQ(bad.status, 400);
  EXPECT_EQ(bad.error, "unknown event 'fly'");
}

TEST(DashboardRequest, RefusesMalformedOversizedAndOutOfRangeWithAReason) {
  const phri::DashboardRequestLimits limits;
  struct Case {
    const char* action;
    std::string body;
    int status;
    const char* reason;
  };
  const Case cases[] = {
      {"event", "{\"event\": ", 400, "malformed JSON"},
      {"event", "[1, 2]", 400, "must be a JSON object"},
      {"event", std::string(2000, ' '), 413, "at most 1024"},
      {"event", R"({"event": "stop", "extra": 1})", 400, "unknown key 'extra'"},
      {"gain", R"({"gain": "stiffness_scale", "value": 9})", 400, "stiffness_scale must be within [0.1, 4], got 9"},
      {"gain", R"({"gain": "stiffness_scale", "value": 0})", 400, "within [0.1, 4]"},
      {"gain", R"({"gain": "ee_gamma", "value": 1.5})", 400, "or -1 (the mode's)"},
      {"gain", R"({"gain": "posture_stiffness", "value": "high"})", 400, "value must be a number"},
      {"gain", R"({"gain": "posture_stiffness", "value": 1e999})", 400, "malformed JSON"},
      {"gain", R"({"gain": "kp", "value": 1})", 400, "unknown gain 'kp'"},
      {"gain", R"({"gain": "ee_gamma"})", 400, "missing key 'value'"},
      {"push", R"({"body": 7, "point": [0, 0, 0], "force": [1, 0, 0]})", 400, "body must be an integer in [0, 6]"},
      {"push", R"({"body": 2, "point": [0, 0], "force": [1, 0, 0]})", 400, "point must be an array of 3 numbers"},
      {"push", R"({"body": 2, "point": [0, 0, 5], "force": [1, 0, 0]})", 400, "within 1 m"},
      {"step", R"({"cycles": 0})", 400, "cycles must be an integer in [1, 10000]"},
      {"launch", "{}", 404, "no action 'launch'"},
      {"gain", R"({"gain": "ee_gamma", "value": 0.3, "value": 1})", 400, "key 'value' given twice"},
      {"push", R"({"body": 2, "point": [0, 0, 0], "force": [1, 0, 0], "force": [2, 0, 0]})", 400, "given twice"},
      {"event", R"({"event": "stop"} trailing)", 400, "malformed JSON"},
  };
  for (const Case& c : cases) {
    const auto r = phri::parse_dashboard_request(c.action, c.body, limits);
    EXPECT_FALSE(r.command) << c.action << " " << c.body.substr(0, 60);
    EXPECT_EQ(r.status, c.status) << c.body.substr(0, 60);
    EXPECT_NE(r.error.find(c.reason), std::string::npos) << "'" << r.error << "' lacks '" << c.reason << "'";
  }
}

TEST(DashboardRequest, CapsAPushAtTheMaximumAndKeepsItsDirection) {
  phri::DashboardRequestLimits limits;
  limits.max_push_N = 100.0;
  const auto r = phri::parse_dashboard_request("push", R"({"body": 6, "point": [0, 0, -0.03], "force": [300, 400, 0]})", limits);
  ASSERT_TRUE(r.command) << r.error;
  EXPECT_NEAR(r.push_applied_N, 100.0, 1e-9);
  EXPECT_NEAR(r.command->push.force_world.x(), 60.0, 1e-9);
  EXPECT_NEAR(r.command->push.force_world.y(), 80.0, 1e-9);
  EXPECT_EQ(r.command->push.body, 6);
  // A force whose norm overflows a double is capped along its direction, not zeroed.
  const auto huge = phri::parse_dashboard_request("push", R"({"body": 6, "point": [0, 0, 0], "force": [3e200, 0, -4e200]})", limits);
  ASSERT_TRUE(huge.command) << huge.error;
  EXPECT_NEAR(huge.push_applied_N, 100.0, 1e-9);
  EXPECT_NEAR(huge.command->push.force_world.x(), 60.0, 1e-9);
  EXPECT_NEAR(huge.command->push.force_world.z(), -80.0, 1e-9);
  const auto gain = phri::parse_dashboard_request("gain", R"({"gain": "ee_gamma", "value": -1})", limits);
  ASSERT_TRUE(gain.command);
  EXPECT_EQ(gain.command->gain.value, -1.0);  // back to the compliance mode's gamma
}

// ---------------------------------------------------------------- the server over HTTP

class DashboardServerTest : public ::testing::Test {
protected:
  DashboardServerTest()
      : controller_(phri::test::gen3_controller_settings()), server_(channel_, controller_, local_settings()),
        client_("127.0.0.1", server_.port()) {}

  httplib::Headers with_token() const { return {{"X-Phri-Token", server_.token()}}; }

  phri::LiveChannel channel_;
  phri::Controller controller_;
  phri::DashboardServer server_;
  httplib::Client client_;
};

TEST_F(DashboardServerTest, WithoutTheTokenEveryAddressIs401AndNothingReachesTheLoop) {
  EXPECT_EQ(server_.token().size(), 32u);
  EXPECT_NE(server_.url().find("http://127.0.0.1:" + std::to_string(server_.port()) + "/?token=" + server_.token()),
            std::string::npos);
  for (const char* path : {"/", "/app.js", "/api/model", "/api/stream", "/api/log", "/api/status", "/vendor/three.module.js"}) {
    auto res = client_.Get(path);
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 401) << path;
    res = client_.Get(std::string(path) + "?token=0123456789abcdef0123456789abcdef");
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 401) << path << " with a wrong token";
  }
  for (const char* action : {"/api/event", "/api/gain", "/api/push", "/api/pause", "/api/run"}) {
    auto res = client_.Post(action, R"({"event": "stop"})", "application/json");
    ASSERT_TRUE(res) << action;
    EXPECT_EQ(res->status, 401) << action;
    res = client_.Post(action, {{"Cookie", "phri_token=nope"}}, R"({"event": "stop"})", "application/json");
    ASSERT_TRUE(res) << action;
    EXPECT_EQ(res->status, 401) << action;
  }
  EXPECT_EQ(queued(channel_), 0);
  EXPECT_EQ(server_.stats().commands, 0u);
}

TEST_F(DashboardServerTest, TheTokenOpensThePageWhichSetsACookieForItsLaterRequests) {
  auto page = client_.Get("/?token=" + server_.token());
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/app.js"), std::string::npos);
  const std::string cookie = page->get_header_value("Set-Cookie");
  EXPECT_NE(cookie.find("phri_token=" + server_.token()), std::string::npos);
  EXPECT_NE(cookie.find("SameSite=Strict"), std::string::npos);
  auto model = client_.Get("/api/model", {{"Cookie", "phri_token=" + server_.token()}});
  ASSERT_TRUE(model);
  EXPECT_EQ(model->status, 200);
  EXPECT_NE(model->body.find("\"end_effector_link\""), std::string::npos);
  EXPECT_NE(model->body.find("\"push_max_N\":100.0"), std::string::npos);
}

TEST_F(DashboardServerTest, BadRequestsAreRefusedWithAReasonAndQueueNothing) {
  struct Case {
    const char* path;
    std::string body;
    int status;
    const char* reason;
  };
  const Case cases[] = {
      {"/api/event", "{not json", 400, "malformed JSON"},
      {"/api/event", std::string(4096, 'x'), 413, "body too large"},
      {"/api/gain", R"({"gain": "stiffness_scale", "value": 40})", 400, "must be within [0.1, 4]"},
      {"/api/gain", R"({"gain": "posture_stiffness", "value": -3})", 400, "must be within [0, 400]"},
      {"/api/push", R"({"body": -1, "point": [0, 0, 0], "force": [1, 0, 0]})", 400, "body must be"},
      {"/api/frobnicate", "{}", 404, "no action"},
  };
  for (const Case& c : cases) {
    auto res = client_.Post(c.path, with_token(), c.body, "application/json");
    ASSERT_TRUE(res) << c.path;
    EXPECT_EQ(res->status, c.status) << c.path << " " << c.body.substr(0, 40);
    EXPECT_NE(res->body.find(c.reason), std::string::npos) << res->body;
  }
  EXPECT_EQ(queued(channel_), 0);
  EXPECT_GE(server_.stats().refused, std::size(cases) - 1);
}

TEST_F(DashboardServerTest, AcceptedRequestsArriveInTheChannelInOrder) {
  const std::pair<const char*, const char*> posts[] = {
      {"/api/event", R"({"event": "full_body_compliance"})"},
      {"/api/gain", R"({"gain": "stiffness_scale", "value": 2.5})"},
      {"/api/push", R"({"body": 6, "point": [0, 0, -0.03], "force": [0, 500, 0]})"},
      {"/api/release", ""},
      {"/api/step", R"({"cycles": 5})"},
  };
  for (const auto& [path, body] : posts) {
    auto res = client_.Post(path, with_token(), body, "application/json");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200) << path << ": " << res->body;
    if (std::string(path) == "/api/push") {
      EXPECT_NE(res->body.find("\"applied_N\":100"), std::string::npos) << res->body;
    }
  }
  phri::LiveCommand c;
  ASSERT_TRUE(channel_.receive(c));
  EXPECT_EQ(c.kind, phri::LiveCommand::Kind::kEvent);
  EXPECT_EQ(c.event, phri::Event::kFullBodyCompliance);
  ASSERT_TRUE(channel_.receive(c));
  EXPECT_EQ(c.kind, phri::LiveCommand::Kind::kGain);
  EXPECT_EQ(c.gain.value, 2.5);
  ASSERT_TRUE(channel_.receive(c));
  EXPECT_EQ(c.kind, phri::LiveCommand::Kind::kPush);
  EXPECT_NEAR(c.push.force_world.norm(), 100.0, 1e-9);
  ASSERT_TRUE(channel_.receive(c));
  EXPECT_EQ(c.kind, phri::LiveCommand::Kind::kRelease);
  ASSERT_TRUE(channel_.receive(c));
  EXPECT_EQ(c.steps, 5);
  EXPECT_FALSE(channel_.receive(c));
}

// ---------------------------------------------------------------- with the run loop

// The dashboard's run: the simulated Gen3 of configs/dashboard.yaml (no timeline, no gamepad).
struct LiveRun {
  LiveRun() : config(load()), robot(config.plant), controller(config.controller), fsm(config.fsm, controller),
              server(channel, controller, local_settings()) {}
  static phri::Config load() {
    phri::Config c = phri::Config::from_yaml_file(kRoot + "/configs/dashboard.yaml");
    c.gamepad.enabled = false;
    return c;
  }
  phri::RunSummary run(double duration_s, bool real_time) {
    phri::RunOptions options;
    options.duration_s = duration_s;
    options.real_time = real_time;
    options.status_line = false;
    options.live = &channel;
    options.pushes = &robot;
    return phri::run_session(robot, controller, fsm, nullptr, nullptr, options, out);
  }
  phri::Config config;
  phri::SimRobot robot;
  phri::Controller controller;
  phri::Fsm fsm;
  phri::LiveChannel channel;
  phri::DashboardServer server;
  std::ostringstream out;
};

// Waits until the loop, paused, has run to robot time `t` (as the server's newest snapshot says).
void wait_paused_at(const phri::DashboardServer& server, double t) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (;;) {
    const phri::DashboardStats s = server.stats();
    if (s.paused && s.time_s >= t - 1e-9) return;
    if (std::chrono::steady_clock::now() > give_up) {
      ADD_FAILURE() << "the loop did not pause at t = " << t << " s (newest snapshot: " << s.time_s << " s)";
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Reads the stream until a frame contains `needle` (or `max_frames` frames went by).
bool stream_shows(const phri::DashboardServer& server, const std::string& needle, int max_frames) {
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(5, 0);
  int frames = 0;
  bool found = false;
  std::string pending;
  client.Get("/api/stream?token=" + server.token(), [&](const char* data, std::size_t size) {
    pending.append(data, size);
    for (std::size_t end; (end = pending.find("\n\n")) != std::string::npos; pending.erase(0, end + 2)) {
      if (pending.compare(0, 5, "data:") != 0) continue;
      ++frames;
      found = found || pending.substr(0, end).find(needle) != std::string::npos;
    }
    return !found && frames < max_frames;
  });
  return found;
}

TEST(DashboardLoop, EventsGainsAndPushesReachTheControllerThroughTheLoopsOnePath) {
  LiveRun run;
  httplib::Client client("127.0.0.1", run.server.port());
  const httplib::Headers token = {{"X-Phri-Token", run.server.token()}};
  // Paused from the first cycle: the requests wait in the channel, then "run" lets the loop go.
  ASSERT_EQ(client.Post("/api/pause", token, "", "application/json")->status, 200);
  std::thread loop([&] { run.run(4.0, false); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_LT(run.server.stats().time_s, 0.0) << "paused before the first cycle: no snapshot yet";
  ASSERT_EQ(client.Post("/api/event", token, R"({"event": "full_body_compliance"})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/gain", token, R"({"gain": "stiffness_scale", "value": 2.0})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/gain", token, R"({"gain": "posture_gamma", "value": 0.5})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/step", token, R"({"cycles": 3})", "application/json")->status, 200);
  wait_paused_at(run.server, 0.001);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const double after_steps = run.robot.state().time_s;
  EXPECT_NEAR(after_steps, 0.003, 1e-9) << "three single steps, then paused again";
  EXPECT_TRUE(stream_shows(run.server, "\"paused\":true", 3));
  EXPECT_EQ(run.robot.state().time_s, after_steps) << "paused: the simulation does not advance";
  const auto paused_step = client.Post("/api/step", token, R"({"cycles": 1})", "application/json");
  EXPECT_EQ(paused_step->body.find("paused to step"), std::string::npos) << paused_step->body;
  ASSERT_EQ(client.Post("/api/run", token, "", "application/json")->status, 200);
  for (int i = 0; i < 200 && run.server.stats().paused; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_FALSE(run.server.stats().paused) << "running again";
  // Stepping the running loop pauses it: the answer says so.
  const auto running_step = client.Post("/api/step", token, R"({"cycles": 1})", "application/json");
  EXPECT_NE(running_step->body.find("the run was paused to step"), std::string::npos) << running_step->body;
  ASSERT_EQ(client.Post("/api/run", token, "", "application/json")->status, 200);
  loop.join();
  const phri::ComplianceController& compliance = run.controller.compliance();
  EXPECT_EQ(compliance.mode(), phri::ComplianceMode::kFullBody);
  EXPECT_EQ(compliance.stiffness_scale(), 2.0);
  EXPECT_EQ(compliance.posture_gamma_override(), 0.5);
  EXPECT_NEAR(run.controller.qp().posture().gamma(), 0.5, 1e-3);
  EXPECT_GE(run.fsm.events_handled(), 1u);
}

TEST(DashboardLoop, ADraggedLinkMovesTheSimulatedArmAndLettingGoEndsThePush) {
  LiveRun run;
  httplib::Client client("127.0.0.1", run.server.port());
  const httplib::Headers token = {{"X-Phri-Token", run.server.token()}};
  ASSERT_EQ(client.Post("/api/pause", token, "", "application/json")->status, 200);
  std::thread loop([&] { run.run(7.0, false); });
  // After the start-up (3 s), full-body compliance, a 30 N push on the end-effector link along +y for 1 s.
  ASSERT_EQ(client.Post("/api/step", token, R"({"cycles": 3000})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/event", token, R"({"event": "full_body_compliance"})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/step", token, R"({"cycles": 500})", "application/json")->status, 200);
  wait_paused_at(run.server, 3.5);
  const double y0 = run.robot.truth().sensor_position_m.y();
  ASSERT_EQ(client.Post("/api/push", token, R"({"body": 6, "point": [0, 0, -0.03], "force": [0, 30, 0]})", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/step", token, R"({"cycles": 400})", "application/json")->status, 200);
  wait_paused_at(run.server, 3.9);
  const double y1 = run.robot.truth().sensor_position_m.y();
  EXPECT_GT(y1 - y0, 0.02) << "a 30 N push for 0.4 s on the end effector in full-body compliance moves it";
  ASSERT_EQ(client.Post("/api/release", token, "", "application/json")->status, 200);
  ASSERT_EQ(client.Post("/api/run", token, "", "application/json")->status, 200);
  loop.join();
  EXPECT_LT(std::abs(run.robot.truth().sensor_position_m.y() - y0), 0.5 * (y1 - y0)) << "released, the arm goes back";
}

// The loop's side of the hand-off allocates nothing: a session's allocations (all made before and
// after its cycles) do not depend on how many cycles it runs, with the page's commands taken and
// a snapshot published every 16 cycles.
TEST(DashboardLoop, TheLoopSideOfTheHandOffAllocatesNothingPerCycle) {
  if (!phri::test::counts_malloc()) GTEST_SKIP() << "allocations are not counted under the sanitizer";
  auto allocations = [](double duration_s) {
    const phri::Config config = LiveRun::load();
    phri::SimRobot robot(config.plant);
    phri::Controller controller(config.controller);
    phri::Fsm fsm(config.fsm, controller);
    phri::LiveChannel channel;
    phri::LiveCommand c;
    c.kind = phri::LiveCommand::Kind::kEvent;
    c.event = phri::Event::kFullBodyCompliance;
    channel.send(c);
    c.kind = phri::LiveCommand::Kind::kGain;
    c.gain = {phri::LiveGain::kStiffnessScale, 2.0};
    channel.send(c);
    c.kind = phri::LiveCommand::Kind::kPush;
    c.push.body = 6;
    c.push.force_world = Eigen::Vector3d(0, 20, 0);
    channel.send(c);
    phri::RunOptions options;
    options.duration_s = duration_s;
    options.status_line = false;
    options.live = &channel;
    options.pushes = &robot;
    std::ostringstream out;
    const phri::test::AllocationCounter count;
    const phri::RunSummary summary = phri::run_session(robot, controller, fsm, nullptr, nullptr, options, out);
    const std::size_t n = count.allocations();
    EXPECT_EQ(controller.compliance().mode(), phri::ComplianceMode::kFullBody);
    EXPECT_GT(channel.published(), 0u);
    EXPECT_FALSE(summary.safe_hold) << out.str();
    return n;
  };
  EXPECT_EQ(allocations(1.0), allocations(3.0));
}

TEST(DashboardLoop, HundredClientsComeAndGoWhileTheLoopRunsWithoutMemoryGrowth) {
  LiveRun run;
  std::thread loop([&] { run.run(9.0, true); });
  auto crowd = [&](int connections, double spread_s) {
    phri::StreamClientsSettings s;
    s.port = run.server.port();
    s.token = run.server.token();
    s.connections = connections;
    s.spread_s = spread_s;
    phri::StreamClients clients(s);
    clients.join();
    return std::pair{clients.served(), clients.failed()};
  };
  const auto warm = crowd(20, 1.0);  // the server's threads and buffers exist after a first wave
  const long before_kb = phri::resident_kb();
  const auto [served, failed] = crowd(100, 4.0);
  const long after_kb = phri::resident_kb();
  loop.join();
  EXPECT_EQ(warm.first, 20);
  EXPECT_EQ(served, 100);
  EXPECT_EQ(failed, 0);
  EXPECT_LT(after_kb - before_kb, 4096) << "resident memory grew from " << before_kb << " kB to " << after_kb << " kB";
  EXPECT_EQ(run.server.stats().streams_open, 0);
  EXPECT_GE(run.server.stats().streams_opened, 120u);
  // The loop never waited: it ran every cycle, and handed over (or dropped) one snapshot per 16.
  EXPECT_EQ(run.robot.state().time_s > 8.999, true);
  EXPECT_EQ(run.channel.published() + run.channel.dropped(), 9000u / 16 + 1);
  EXPECT_EQ(run.out.str().find("SAFE HOLD"), std::string::npos) << run.out.str();
}

}  // namespace
