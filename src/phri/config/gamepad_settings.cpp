#include <phri/config/gamepad_settings.hpp>

namespace phri {

std::string_view to_string(GamepadButton button) {
  switch (button) {
    case GamepadButton::kCross: return "cross";
    case GamepadButton::kCircle: return "circle";
    case GamepadButton::kSquare: return "square";
    case GamepadButton::kTriangle: return "triangle";
    case GamepadButton::kShare: return "share";
    case GamepadButton::kPs: return "ps";
    case GamepadButton::kOptions: return "options";
    case GamepadButton::kL3: return "l3";
    case GamepadButton::kR3: return "r3";
    case GamepadButton::kL1: return "l1";
    case GamepadButton::kR1: return "r1";
    case GamepadButton::kDpadUp: return "dpad_up";
    case GamepadButton::kDpadDown: return "dpad_down";
    case GamepadButton::kDpadLeft: return "dpad_left";
    case GamepadButton::kDpadRight: return "dpad_right";
    case GamepadButton::kTouchpad: return "touchpad";
  }
  return "unknown";
}

GamepadMapping GamepadMapping::ds4() {
  GamepadMapping m;
  auto bind = [&](GamepadButton b, Event e) { m.buttons[static_cast<std::size_t>(b)] = e; };
  bind(GamepadButton::kDpadUp, Event::kNullSpaceCompliance);
  bind(GamepadButton::kDpadRight, Event::kFullBodyCompliance);
  bind(GamepadButton::kDpadDown, Event::kDynamicScenario);
  bind(GamepadButton::kDpadLeft, Event::kStaticScenario);
  bind(GamepadButton::kCross, Event::kDualCompliance);
  bind(GamepadButton::kSquare, Event::kStiffCompliance);
  bind(GamepadButton::kTriangle, Event::kToggleScenario);
  bind(GamepadButton::kCircle, Event::kToggleLoop);
  bind(GamepadButton::kR1, Event::kCustomLoop);
  bind(GamepadButton::kL1, Event::kKinovaTorqueLoop);
  bind(GamepadButton::kOptions, Event::kStiffnessUp);
  bind(GamepadButton::kShare, Event::kStiffnessDown);
  bind(GamepadButton::kTouchpad, Event::kStopScenario);
  bind(GamepadButton::kPs, Event::kStop);
  m.l2 = Event::kKinovaTorqueHighVelocityLoop;
  return m;
}

}  // namespace phri
