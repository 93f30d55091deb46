#include <phri/app/gamepad.hpp>

#include <SDL2/SDL.h>

#include <chrono>
#include <cstdio>

namespace phri {

std::optional<Event> GamepadMapper::map(const GamepadInput& input) {
  switch (input.kind) {
    case GamepadInput::Kind::kButtonDown: {
      const auto i = static_cast<std::size_t>(input.button);
      return i < mapping_.buttons.size() ? mapping_.buttons[i] : std::nullopt;
    }
    case GamepadInput::Kind::kAxis: {
      auto trigger = [&](bool& pressed, const std::optional<Event>& event) -> std::optional<Event> {
        if (!pressed && input.value >= mapping_.trigger_press) {
          pressed = true;
          return event;
        }
        if (pressed && input.value <= mapping_.trigger_release) pressed = false;
        return std::nullopt;
      };
      if (input.axis == GamepadAxis::kL2) return trigger(l2_pressed_, mapping_.l2);
      if (input.axis == GamepadAxis::kR2) return trigger(r2_pressed_, mapping_.r2);
      return std::nullopt;
    }
    case GamepadInput::Kind::kConnected:
    case GamepadInput::Kind::kDisconnected:
      // A pad that left with a trigger held must not fire when it (or another) comes back.
      l2_pressed_ = r2_pressed_ = false;
      return std::nullopt;
    case GamepadInput::Kind::kButtonUp:
      return std::nullopt;
  }
  return std::nullopt;
}

// ------------------------------------------------------------------------------------ SDL source
namespace {

constexpr Uint32 kSubsystems = SDL_INIT_EVENTS | SDL_INIT_GAMECONTROLLER;

std::optional<GamepadButton> from_sdl(Uint8 button) {
  switch (button) {
    case SDL_CONTROLLER_BUTTON_A: return GamepadButton::kCross;
    case SDL_CONTROLLER_BUTTON_B: return GamepadButton::kCircle;
    case SDL_CONTROLLER_BUTTON_X: return GamepadButton::kSquare;
    case SDL_CONTROLLER_BUTTON_Y: return GamepadButton::kTriangle;
    case SDL_CONTROLLER_BUTTON_BACK: return GamepadButton::kShare;
    case SDL_CONTROLLER_BUTTON_GUIDE: return GamepadButton::kPs;
    case SDL_CONTROLLER_BUTTON_START: return GamepadButton::kOptions;
    case SDL_CONTROLLER_BUTTON_LEFTSTICK: return GamepadButton::kL3;
    case SDL_CONTROLLER_BUTTON_RIGHTSTICK: return GamepadButton::kR3;
    case SDL_CONTROLLER_BUTTON_LEFTSHOULDER: return GamepadButton::kL1;
    case SDL_CONTROLLER_BUTTON_RIGHTSHOULDER: return GamepadButton::kR1;
    case SDL_CONTROLLER_BUTTON_DPAD_UP: return GamepadButton::kDpadUp;
    case SDL_CONTROLLER_BUTTON_DPAD_DOWN: return GamepadButton::kDpadDown;
    case SDL_CONTROLLER_BUTTON_DPAD_LEFT: return GamepadButton::kDpadLeft;
    case SDL_CONTROLLER_BUTTON_DPAD_RIGHT: return GamepadButton::kDpadRight;
#if SDL_VERSION_ATLEAST(2, 0, 14)
    case SDL_CONTROLLER_BUTTON_TOUCHPAD: return GamepadButton::kTouchpad;
#endif
    default: return std::nullopt;
  }
}

std::optional<GamepadAxis> axis_from_sdl(Uint8 axis) {
  switch (axis) {
    case SDL_CONTROLLER_AXIS_LEFTX: return GamepadAxis::kLeftX;
    case SDL_CONTROLLER_AXIS_LEFTY: return GamepadAxis::kLeftY;
    case SDL_CONTROLLER_AXIS_RIGHTX: return GamepadAxis::kRightX;
    case SDL_CONTROLLER_AXIS_RIGHTY: return GamepadAxis::kRightY;
    case SDL_CONTROLLER_AXIS_TRIGGERLEFT: return GamepadAxis::kL2;
    case SDL_CONTROLLER_AXIS_TRIGGERRIGHT: return GamepadAxis::kR2;
    default: return std::nullopt;
  }
}

}  // namespace

SdlGamepadSource::~SdlGamepadSource() { close(); }

bool SdlGamepadSource::open() {
  if (opened_) return true;
  // No window: controller events must flow without focus; and leave SIGINT/SIGTERM to the program.
  SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
  SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
  if (SDL_InitSubSystem(kSubsystems) != 0) {
    notify(std::string("SDL2 game controllers unavailable (") + SDL_GetError() + "): no gamepad events");
    return false;
  }
  opened_ = true;
  // Pads present now arrive as SDL_CONTROLLERDEVICEADDED events at the first poll.
  return true;
}

void SdlGamepadSource::close() {
  if (opened_) {
    for (Controller& c : controllers_) SDL_GameControllerClose(static_cast<SDL_GameController*>(c.handle));
    controllers_.clear();
    SDL_QuitSubSystem(kSubsystems);
    opened_ = false;
  }
  // SDL keeps per-thread data (its error message buffer) that a thread it did not create would
  // leak on exit; this frees the calling thread's.
  SDL_TLSCleanup();
}

bool SdlGamepadSource::poll(GamepadInput& out) {
  if (!opened_) return false;
  SDL_Event e;
  while (SDL_PollEvent(&e) != 0) {
    switch (e.type) {
      case SDL_CONTROLLERDEVICEADDED: {
        // e.cdevice.which: a device index here.
        SDL_GameController* pad = SDL_GameControllerOpen(e.cdevice.which);
        if (pad == nullptr) {
          notify(std::string("a controller was plugged in but cannot be opened: ") + SDL_GetError());
          continue;
        }
        const int instance = SDL_JoystickInstanceID(SDL_GameControllerGetJoystick(pad));
        bool known = false;
        for (const Controller& c : controllers_) known = known || c.instance == instance;
        if (known) {
          SDL_GameControllerClose(pad);  // SDL reference-counts opens; keep one
          continue;
        }
        controllers_.push_back({instance, pad});
        const char* name = SDL_GameControllerName(pad);
        notify(std::string("connected ") + (name != nullptr ? name : "a controller"));
        out = GamepadInput{GamepadInput::Kind::kConnected, {}, {}, 0.0, instance};
        return true;
      }
      case SDL_CONTROLLERDEVICEREMOVED: {
        // e.cdevice.which: an instance id here.
        const int instance = e.cdevice.which;
        for (std::size_t i = 0; i < controllers_.size(); ++i) {
          if (controllers_[i].instance != instance) continue;
          SDL_GameControllerClose(static_cast<SDL_GameController*>(controllers_[i].handle));
          controllers_.erase(controllers_.begin() + static_cast<std::ptrdiff_t>(i));
          notify("controller disconnected");
          out = GamepadInput{GamepadInput::Kind::kDisconnected, {}, {}, 0.0, instance};
          return true;
        }
        continue;  // not one of ours
      }
      case SDL_CONTROLLERBUTTONDOWN:
      case SDL_CONTROLLERBUTTONUP: {
        const auto button = from_sdl(e.cbutton.button);
        if (!button) continue;
        out = GamepadInput{e.type == SDL_CONTROLLERBUTTONDOWN ? GamepadInput::Kind::kButtonDown
                                                              : GamepadInput::Kind::kButtonUp,
                           *button, {}, 0.0, e.cbutton.which};
        return true;
      }
      case SDL_CONTROLLERAXISMOTION: {
        const auto axis = axis_from_sdl(e.caxis.axis);
        if (!axis) continue;
        const double value = static_cast<double>(e.caxis.value) / 32767.0;
        out = GamepadInput{GamepadInput::Kind::kAxis, {}, *axis, value < -1.0 ? -1.0 : value, e.caxis.which};
        return true;
      }
      default:
        continue;  // joystick-level duplicates, quit requests, ...
    }
  }
  return false;
}

// ------------------------------------------------------------------------------------ Gamepad
Gamepad::Gamepad(const GamepadSettings& settings, std::unique_ptr<GamepadSource> source)
    : settings_(settings),
      source_(source ? std::move(source) : std::make_unique<SdlGamepadSource>()),
      mapper_(settings.mapping),
      queue_(settings.queue_capacity) {
  if (!settings_.notice) {
    settings_.notice = [](const std::string& text) { std::fprintf(stderr, "phri: gamepad: %s\n", text.c_str()); };
  }
}

Gamepad::~Gamepad() { stop(); }

void Gamepad::say(const std::string& text) {
  if (!text.empty()) settings_.notice(text);
}

void Gamepad::open_source() {
  if (opened_) return;
  opened_ = true;
  if (!settings_.enabled) return;
  available_ = source_->open();
  say(source_->take_notice());
}

int Gamepad::drain_source() {
  if (!available()) return 0;
  int queued = 0;
  GamepadInput input;
  while (source_->poll(input)) {
    if (const std::optional<Event> event = mapper_.map(input)) {
      if (queue_.try_push(*event)) {
        ++queued;
        events_.fetch_add(1, std::memory_order_relaxed);
      } else {
        dropped_.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
  say(source_->take_notice());
  return queued;
}

int Gamepad::pump() {
  open_source();
  return drain_source();
}

void Gamepad::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    open_source();
    const auto period = std::chrono::milliseconds(settings_.poll_interval_ms);
    while (available() && running_.load(std::memory_order_relaxed)) {  // unavailable: nothing will ever come
      drain_source();
      std::this_thread::sleep_for(period);
    }
    source_->close();  // in the thread that opened it
  });
}

void Gamepad::stop() {
  if (running_.exchange(false) && thread_.joinable()) {
    thread_.join();
  } else if (opened_ && !thread_.joinable()) {
    source_->close();  // pump() mode: closed by the thread that polled
  }
}

}  // namespace phri
