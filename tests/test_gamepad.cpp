// ctest-labels: unit
// phri::Gamepad: the DS4 mapping table button by button, edge triggering and the analog trigger's
// hysteresis, hot-plug without events, a source that cannot open (no SDL, CI), the background
// thread, and the real SDL2 path fed with synthetic SDL events (SDL_PushEvent works without any
// device once the events and game-controller subsystems are up).
#include <phri/app/gamepad.hpp>

#include "allocation_counter.hpp"

#include <SDL2/SDL.h>
#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

namespace {

using phri::Event;
using phri::GamepadButton;
using phri::GamepadInput;

GamepadInput down(GamepadButton b) { return {GamepadInput::Kind::kButtonDown, b, {}, 0.0, 0}; }
GamepadInput up(GamepadButton b) { return {GamepadInput::Kind::kButtonUp, b, {}, 0.0, 0}; }
GamepadInput axis(phri::GamepadAxis a, double v) { return {GamepadInput::Kind::kAxis, {}, a, v, 0}; }

// A scripted source; thread-safe so that the test can feed it while the gamepad thread polls.
class FakeSource final : public phri::GamepadSource {
public:
  explicit FakeSource(bool can_open = true) : can_open_(can_open) {}
  bool open() override {
    if (!can_open_) notify("no controller subsystem (fake)");
    return can_open_;
  }
  bool poll(GamepadInput& out) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (inputs_.empty()) return false;
    out = inputs_.front();
    inputs_.pop_front();
    return true;
  }
  void feed(const GamepadInput& input) {
    std::lock_guard<std::mutex> lock(mutex_);
    inputs_.push_back(input);
  }

private:
  bool can_open_;
  std::mutex mutex_;
  std::deque<GamepadInput> inputs_;
};

std::vector<Event> drain(phri::Gamepad& pad) {
  std::vector<Event> out;
  Event e;
  while (pad.poll(e)) out.push_back(e);
  return out;
}

TEST(GamepadMapper, Ds4TableButtonByButton) {
  phri::GamepadMapper mapper;
  const std::pair<GamepadButton, Event> table[] = {
      {GamepadButton::kDpadUp, Event::kNullSpaceCompliance},
      {GamepadButton::kDpadRight, Event::kFullBodyCompliance},
      {GamepadButton::kDpadDown, Event::kDynamicScenario},
      {GamepadButton::kDpadLeft, Event::kStaticScenario},
      {GamepadButton::kCross, Event::kDualCompliance},
      {GamepadButton::kSquare, Event::kStiffCompliance},
      {GamepadButton::kTriangle, Event::kToggleScenario},
      {GamepadButton::kCircle, Event::kToggleLoop},
      {GamepadButton::kR1, Event::kCustomLoop},
      {GamepadButton::kL1, Event::kKinovaTorqueLoop},
      {GamepadButton::kOptions, Event::kStiffnessUp},
      {GamepadButton::kShare, Event::kStiffnessDown},
      {GamepadButton::kTouchpad, Event::kStopScenario},
      {GamepadButton::kPs, Event::kStop},
  };
  for (const auto& [button, event] : table) {
    const auto mapped = mapper.map(down(button));
    ASSERT_TRUE(mapped.has_value()) << phri::to_string(button);
    EXPECT_EQ(*mapped, event) << phri::to_string(button) << " -> " << phri::to_string(*mapped);
    EXPECT_FALSE(mapper.map(up(button)).has_value()) << "a release is no event";
  }
  for (GamepadButton unmapped : {GamepadButton::kL3, GamepadButton::kR3}) {
    EXPECT_FALSE(mapper.map(down(unmapped)).has_value());
  }
  // Every event but toggles of loops by name is reachable: all four loops, all four modes.
  EXPECT_EQ(mapper.mapping().l2, Event::kKinovaTorqueHighVelocityLoop);
}

TEST(GamepadMapper, TriggerFiresOnceWithHysteresisAndRearmsAfterUnplug) {
  phri::GamepadMapper mapper;
  using A = phri::GamepadAxis;
  EXPECT_FALSE(mapper.map(axis(A::kL2, 0.2)));
  EXPECT_EQ(mapper.map(axis(A::kL2, 0.6)), Event::kKinovaTorqueHighVelocityLoop);
  EXPECT_FALSE(mapper.map(axis(A::kL2, 0.9)));  // still held
  EXPECT_FALSE(mapper.map(axis(A::kL2, 0.4)));  // inside the hysteresis band: still held
  EXPECT_FALSE(mapper.map(axis(A::kL2, 0.6)));
  EXPECT_FALSE(mapper.map(axis(A::kL2, 0.25)));  // released
  EXPECT_EQ(mapper.map(axis(A::kL2, 0.55)), Event::kKinovaTorqueHighVelocityLoop);
  // Unplugged with L2 held: the next press after re-plugging fires.
  EXPECT_FALSE(mapper.map({GamepadInput::Kind::kDisconnected, {}, {}, 0.0, 0}));
  EXPECT_FALSE(mapper.map({GamepadInput::Kind::kConnected, {}, {}, 0.0, 1}));
  EXPECT_EQ(mapper.map(axis(A::kL2, 0.7)), Event::kKinovaTorqueHighVelocityLoop);
  // R2 and the sticks map to nothing.
  EXPECT_FALSE(mapper.map(axis(A::kR2, 1.0)));
  EXPECT_FALSE(mapper.map(axis(A::kLeftX, 1.0)));
  EXPECT_FALSE(mapper.map(axis(A::kRightY, -1.0)));
}

TEST(Gamepad, FakeSourceEventsInOrderAndPollDoesNotAllocate) {
  auto source = std::make_unique<FakeSource>();
  FakeSource* feed = source.get();
  phri::GamepadSettings settings;
  std::vector<std::string> notices;
  settings.notice = [&](const std::string& t) { notices.push_back(t); };
  phri::Gamepad pad(settings, std::move(source));
  EXPECT_EQ(pad.pump(), 0);
  EXPECT_TRUE(pad.available());
  feed->feed({GamepadInput::Kind::kConnected, {}, {}, 0.0, 3});
  feed->feed(down(GamepadButton::kCross));
  feed->feed(up(GamepadButton::kCross));
  feed->feed(down(GamepadButton::kR1));
  feed->feed(axis(phri::GamepadAxis::kL2, 1.0));
  feed->feed({GamepadInput::Kind::kDisconnected, {}, {}, 0.0, 3});  // unplugged: nothing
  feed->feed(down(GamepadButton::kPs));
  EXPECT_EQ(pad.pump(), 4);
  std::vector<Event> events;
  std::size_t allocations = 0;
  {
    events.reserve(16);
    phri::test::AllocationCounter count;
    Event e;
    while (pad.poll(e)) events.push_back(e);
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  const std::vector<Event> expected = {Event::kDualCompliance, Event::kCustomLoop,
                                       Event::kKinovaTorqueHighVelocityLoop, Event::kStop};
  EXPECT_EQ(events, expected);
  EXPECT_TRUE(notices.empty());
}

TEST(Gamepad, SourceThatCannotOpenGivesOneNoticeAndNoEvents) {
  std::vector<std::string> notices;
  phri::GamepadSettings settings;
  settings.notice = [&](const std::string& t) { notices.push_back(t); };
  auto source = std::make_unique<FakeSource>(false);
  FakeSource* feed = source.get();
  phri::Gamepad pad(settings, std::move(source));
  feed->feed(down(GamepadButton::kCross));
  EXPECT_EQ(pad.pump(), 0);
  EXPECT_EQ(pad.pump(), 0);
  EXPECT_FALSE(pad.available());
  EXPECT_TRUE(drain(pad).empty());
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_NE(notices[0].find("no controller"), std::string::npos);
  // The thread variant ends at once and stops cleanly.
  pad.start();
  pad.stop();
}

TEST(Gamepad, DisabledOpensNothing) {
  phri::GamepadSettings settings;
  settings.enabled = false;
  auto source = std::make_unique<FakeSource>();
  FakeSource* feed = source.get();
  phri::Gamepad pad(settings, std::move(source));
  feed->feed(down(GamepadButton::kCross));
  EXPECT_EQ(pad.pump(), 0);
  EXPECT_FALSE(pad.available());
}

TEST(Gamepad, BackgroundThreadDeliversEvents) {
  auto source = std::make_unique<FakeSource>();
  FakeSource* feed = source.get();
  phri::GamepadSettings settings;
  settings.poll_interval_ms = 1;
  phri::Gamepad pad(settings, std::move(source));
  pad.start();
  feed->feed(down(GamepadButton::kDpadDown));
  feed->feed(down(GamepadButton::kTriangle));
  std::vector<Event> events;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (events.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    Event e;
    if (pad.poll(e)) events.push_back(e);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  pad.stop();
  const std::vector<Event> expected = {Event::kDynamicScenario, Event::kToggleScenario};
  EXPECT_EQ(events, expected);
}

TEST(Gamepad, FullQueueDropsAndCounts) {
  auto source = std::make_unique<FakeSource>();
  FakeSource* feed = source.get();
  phri::GamepadSettings settings;
  settings.queue_capacity = 4;
  phri::Gamepad pad(settings, std::move(source));
  for (int i = 0; i < 10; ++i) feed->feed(down(GamepadButton::kOptions));
  EXPECT_EQ(pad.pump(), 4);
  EXPECT_EQ(pad.dropped(), 6u);
  EXPECT_EQ(drain(pad).size(), 4u);
}

// The SDL2 source itself, with synthetic SDL events: button and axis events from an instance
// that was never opened still map (no device is needed), a plug-in event for a device that does
// not exist and an unplug of an unknown instance are survived without events.
TEST(SdlGamepad, SyntheticSdlEventsMapThroughTheRealSource) {
  std::vector<std::string> notices;
  phri::GamepadSettings settings;
  settings.notice = [&](const std::string& t) { notices.push_back(t); };
  phri::Gamepad pad(settings);  // SdlGamepadSource
  pad.pump();
  if (!pad.available()) {
    GTEST_SKIP() << "SDL2 game controllers unavailable here: " << (notices.empty() ? "" : notices[0]);
  }
  drain(pad);  // a pad actually plugged into this machine could have said hello
  notices.clear();
  auto push = [](SDL_Event e) { ASSERT_EQ(SDL_PushEvent(&e), 1) << SDL_GetError(); };
  SDL_Event e{};
  e.type = SDL_CONTROLLERBUTTONDOWN;
  e.cbutton.which = 4242;
  e.cbutton.button = SDL_CONTROLLER_BUTTON_A;
  e.cbutton.state = SDL_PRESSED;
  push(e);
  e.type = SDL_CONTROLLERBUTTONUP;
  e.cbutton.state = SDL_RELEASED;
  push(e);
  e = SDL_Event{};
  e.type = SDL_CONTROLLERDEVICEADDED;
  e.cdevice.which = 99;  // no such device index
  push(e);
  e = SDL_Event{};
  e.type = SDL_CONTROLLERDEVICEREMOVED;
  e.cdevice.which = 4243;  // no such instance
  push(e);
  e = SDL_Event{};
  e.type = SDL_CONTROLLERBUTTONDOWN;
  e.cbutton.which = 4242;
  e.cbutton.button = SDL_CONTROLLER_BUTTON_DPAD_RIGHT;
  e.cbutton.state = SDL_PRESSED;
  push(e);
  e = SDL_Event{};
  e.type = SDL_CONTROLLERAXISMOTION;
  e.caxis.which = 4242;
  e.caxis.axis = SDL_CONTROLLER_AXIS_TRIGGERLEFT;
  e.caxis.value = 32767;
  push(e);
  e.caxis.value = 0;
  push(e);
  e = SDL_Event{};
  e.type = SDL_CONTROLLERBUTTONDOWN;
  e.cbutton.which = 4242;
  e.cbutton.button = SDL_CONTROLLER_BUTTON_GUIDE;
  push(e);
  EXPECT_EQ(pad.pump(), 4);
  const std::vector<Event> expected = {Event::kDualCompliance, Event::kFullBodyCompliance,
                                       Event::kKinovaTorqueHighVelocityLoop, Event::kStop};
  EXPECT_EQ(drain(pad), expected);
  ASSERT_FALSE(notices.empty());
  EXPECT_NE(notices[0].find("cannot be opened"), std::string::npos) << notices[0];
  pad.stop();
}

// The same through the background thread, which initialises SDL itself; SDL_PushEvent is
// thread-safe, so the test thread plays the device.
TEST(SdlGamepad, BackgroundThreadWithSdl) {
  std::vector<std::string> notices;
  std::mutex notices_mutex;
  phri::GamepadSettings settings;
  settings.poll_interval_ms = 1;
  settings.notice = [&](const std::string& t) {
    std::lock_guard<std::mutex> lock(notices_mutex);
    notices.push_back(t);
  };
  phri::Gamepad pad(settings);
  pad.start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!pad.available() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!pad.available()) {
    pad.stop();
    GTEST_SKIP() << "SDL2 game controllers unavailable here";
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  drain(pad);
  SDL_Event e{};
  e.type = SDL_CONTROLLERBUTTONDOWN;
  e.cbutton.which = 7;
  e.cbutton.button = SDL_CONTROLLER_BUTTON_B;
  ASSERT_EQ(SDL_PushEvent(&e), 1);
  std::vector<Event> events;
  while (events.empty() && std::chrono::steady_clock::now() < deadline) {
    Event ev;
    if (pad.poll(ev)) events.push_back(ev);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  pad.stop();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], Event::kToggleLoop);
}

}  // namespace
