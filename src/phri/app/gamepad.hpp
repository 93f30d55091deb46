#pragma once
// phri::Gamepad: a DualShock 4 (or any controller SDL2 knows) turned into phri::Event values for
// the FSM, as in the paper's demo where the operator switches compliance modes, low-level loops
// and scenarios live from a DS4 mounted on the end effector.
//
// Three layers, each testable alone:
//   GamepadSource   raw inputs (button down/up, axis, connected/disconnected). SdlGamepadSource
//                   reads SDL2's GameController API (SDL_INIT_GAMECONTROLLER | SDL_INIT_EVENTS
//                   only: no window, no video); tests use a fake source, or push SDL events.
//   GamepadMapper   raw input -> Event, edge-triggered (a press is one event; holding repeats
//                   nothing), analog L2 with hysteresis. The mapping is a table (GamepadMapping).
//   Gamepad         owns a source and a mapper; either a background thread polls the source
//                   (start()) or the caller does (pump()); events wait in a lock-free queue that
//                   the control thread reads with poll(Event&) — no allocation, no lock, no I/O.
//
// Hot-plug: a pad plugged in at any time is opened (SDL_CONTROLLERDEVICEADDED), an unplugged one
// closed (..._REMOVED); while none is connected there are simply no events. If SDL cannot
// initialise (no udev, CI containers...) the gamepad says so once through the notice callback
// and produces no events; the run goes on.
//
// DS4 mapping (GamepadMapping::ds4(); the paper's demo in parentheses where it differs,
// paper_parameters.md section 6; SDL's names of the buttons in brackets):
//
//   | DS4 button          | SDL [name]          | event                            |
//   |---------------------|---------------------|----------------------------------|
//   | D-pad Up            | DPAD_UP             | null_space_compliance            |
//   | D-pad Right         | DPAD_RIGHT          | full_body_compliance             |
//   | D-pad Down          | DPAD_DOWN           | dynamic_scenario                 |
//   | D-pad Left          | DPAD_LEFT           | static_scenario (paper: min-jerk/Fitts mode) |
//   | Cross               | A                   | dual_compliance                  |
//   | Square              | X                   | stiff_compliance (paper: toggle EE compliance) |
//   | Triangle            | Y                   | toggle_scenario static <-> dynamic (paper: toggle posture compliance) |
//   | Circle              | B                   | toggle_loop position <-> last torque loop |
//   | R1                  | RIGHTSHOULDER       | custom_loop (the paper's torque loop) |
//   | L1                  | LEFTSHOULDER        | kinova_torque_loop               |
//   | L2 (analog, > 0.5)  | TRIGGERLEFT         | kinova_torque_high_velocity_loop |
//   | Options             | START               | stiffness_up                     |
//   | Share               | BACK                | stiffness_down                   |
//   | Touchpad click      | TOUCHPAD            | stop_scenario (brake and hold)   |
//   | PS                  | GUIDE               | stop (brake, hold, end of session) |
//   | R2, sticks, L3, R3  |                     | (none)                           |
#include <phri/config/event.hpp>
#include <phri/config/gamepad_settings.hpp>
#include <phri/core/spsc_ring.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace phri {

/// One raw input of a controller.
struct GamepadInput {
  enum class Kind : std::uint8_t { kButtonDown, kButtonUp, kAxis, kConnected, kDisconnected };
  Kind kind = Kind::kButtonDown;
  GamepadButton button = GamepadButton::kCross;  ///< kButtonDown / kButtonUp
  GamepadAxis axis = GamepadAxis::kLeftX;        ///< kAxis
  double value = 0.0;  ///< kAxis: sticks in [-1, 1], triggers in [0, 1]
  int device = -1;     ///< controller instance (SDL joystick instance id)
};

/// Where raw inputs come from. Not thread-safe: one thread opens, polls and closes it.
class GamepadSource {
public:
  virtual ~GamepadSource() = default;
  /// Prepares the source; false when no controller can ever be read (then notice() says why).
  virtual bool open() = 0;
  /// The next pending input, if any (never blocks).
  virtual bool poll(GamepadInput& out) = 0;
  virtual void close() {}
  /// Human-readable news (why open failed, a pad connected or left); cleared by take_notice().
  std::string take_notice() { return std::exchange(notice_, std::string()); }

protected:
  void notify(std::string text) { notice_ = notice_.empty() ? std::move(text) : notice_ + "; " + text; }

private:
  std::string notice_;
};

/// SDL2 GameController input. open() initialises SDL's events and game-controller subsystems
/// (reference counted: SDL_InitSubSystem / SDL_QuitSubSystem) in the calling thread, which must
/// then be the only one to poll and close (close() also frees SDL's data for that thread).
class SdlGamepadSource final : public GamepadSource {
public:
  SdlGamepadSource() = default;
  ~SdlGamepadSource() override;
  bool open() override;
  bool poll(GamepadInput& out) override;
  void close() override;
  int connected() const { return static_cast<int>(controllers_.size()); }

private:
  struct Controller {
    int instance = -1;
    void* handle = nullptr;  // SDL_GameController*
  };
  bool opened_ = false;
  std::vector<Controller> controllers_;
};

/// Raw inputs -> events. Allocation-free.
class GamepadMapper {
public:
  explicit GamepadMapper(const GamepadMapping& mapping = GamepadMapping::ds4()) : mapping_(mapping) {}
  std::optional<Event> map(const GamepadInput& input);
  const GamepadMapping& mapping() const { return mapping_; }

private:
  GamepadMapping mapping_;
  bool l2_pressed_ = false;
  bool r2_pressed_ = false;
};

class Gamepad {
public:
  /// source: null for SDL (SdlGamepadSource).
  explicit Gamepad(const GamepadSettings& settings = {}, std::unique_ptr<GamepadSource> source = nullptr);
  ~Gamepad();
  Gamepad(const Gamepad&) = delete;
  Gamepad& operator=(const Gamepad&) = delete;

  /// Polls the source in a background thread (opened there) every poll_interval_ms.
  void start();
  /// Stops the thread and closes the source.
  void stop();
  /// Alternative to start(): opens the source on first call, then maps every pending input in
  /// the calling thread. Returns the number of events queued.
  int pump();

  /// Control thread: the next event, oldest first. Never blocks or allocates.
  bool poll(Event& out) noexcept { return queue_.try_pop(out); }

  /// The source opened (false before, or when SDL is unavailable).
  bool available() const { return available_.load(std::memory_order_relaxed); }
  /// Events lost because the queue was full (nobody polled).
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  std::uint64_t events() const { return events_.load(std::memory_order_relaxed); }

private:
  void open_source();
  int drain_source();
  void say(const std::string& text);

  GamepadSettings settings_;
  std::unique_ptr<GamepadSource> source_;
  GamepadMapper mapper_;
  SpscRing<Event> queue_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  bool opened_ = false;
  std::atomic<bool> available_{false};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> events_{0};
};

}  // namespace phri
