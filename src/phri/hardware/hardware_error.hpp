#pragma once
// phri::HardwareError: a device (the arm, a sensor) cannot be used as it is; thrown while
// connecting and starting, never inside the control cycle. subject(): the device, e.g.
// "kortex 192.168.1.10"; the message is one line, "kortex 192.168.1.10: the arm reports 6
// actuators, the robot has 7 joints".
#include <phri/core/error.hpp>

namespace phri {

class HardwareError : public SubjectError {
public:
  using SubjectError::SubjectError;
};

}  // namespace phri
