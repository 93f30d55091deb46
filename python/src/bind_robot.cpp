// phri/robot for Python: RobotState (what the arm reports), RobotCommand (what it is told), the
// low-level modes and write statuses, and RobotInterface (read/write), which SimRobot implements.
// State and command vectors are numpy views of the C++ buffers: a state's views are read-only
// and show the robot's latest read(); a command's are writeable, so `command.current_A[:] = i`
// writes straight into what robot.write(command) sends. Assigning a whole vector copies it in,
// size-checked (the buffers are never reallocated under a view).
#include "bindings.hpp"

#include <phri/robot/robot_interface.hpp>

namespace phri::python {
namespace {

template <class Owner>
void vector_property(py::class_<Owner>& c, const char* name, Eigen::VectorXd Owner::*member, bool writeable, const char* doc) {
  const std::string setter_name = std::string(name);
  c.def_property(
      name, [member, writeable](py::object self) { return vector_view(self.cast<Owner&>().*member, self, writeable); },
      [member, setter_name](Owner& self, const Eigen::Ref<const Eigen::VectorXd>& value) {
        assign_same_size(self.*member, value, setter_name.c_str());
      },
      doc);
}

void bind_state(py::module_& m) {
  py::class_<SignalStatus>(m, "SignalStatus", "Validity and freshness of one sensor signal.")
      .def(py::init<>())
      .def_readwrite("valid", &SignalStatus::valid)
      .def_readwrite("sequence", &SignalStatus::sequence, "Number of samples so far.")
      .def_readwrite("stamp_s", &SignalStatus::stamp_s, "Robot time of the sample [s].");
  py::class_<RobotState> c(m, "RobotState",
                           "What the arm reports once per cycle (noisy, quantised sensors). Vectors are read-only views "
                           "of the C++ state: a state returned by read() shows the next read() too (copy() keeps it).");
  c.def(py::init<int>(), py::arg("dof"))
      .def("copy", [](const RobotState& s) { return RobotState(s); }, "A deep copy (its own buffers).")
      .def_readwrite("time_s", &RobotState::time_s, "Robot time at the end of the cycle [s].")
      .def_readwrite("cycle", &RobotState::cycle, "Completed control cycles.")
      .def_readwrite("mode", &RobotState::mode, "Low-level mode that ran during the last cycle.");
  vector_property(c, "q_rad", &RobotState::q_rad, false, "Joint positions [rad] (view).");
  vector_property(c, "qd_rad_s", &RobotState::qd_rad_s, false, "Joint velocities [rad/s] (view).");
  vector_property(c, "tau_sensor_Nm", &RobotState::tau_sensor_Nm, false, "Joint torque sensors [N m] (view).");
  vector_property(c, "current_A", &RobotState::current_A, false, "Motor currents [A] (view).");
  c.def_property_readonly(
       "wrench_sensor",
       [](py::object self) { return vector_view(self.cast<const RobotState&>().wrench_sensor.data(), 6, self); },
       "F/T sensor (force [N]; moment [N m]) in the sensor frame (view).")
      .def_readwrite("joints", &RobotState::joints)
      .def_readwrite("torque", &RobotState::torque)
      .def_readwrite("current", &RobotState::current)
      .def_readwrite("wrench", &RobotState::wrench)
      .def_readwrite("fault", &RobotState::fault, "The robot stopped obeying commands.")
      .def_readwrite("stop_requested", &RobotState::stop_requested,
                     "The robot still obeys but asks for a safe stop (a degraded link).")
      .def_readwrite("last_write_status", &RobotState::last_write_status)
      .def_readwrite("rejected_writes", &RobotState::rejected_writes);
}

void bind_command(py::module_& m) {
  py::class_<RobotCommand> c(m, "RobotCommand",
                             "One low-level command; only the set-point of `mode` is read. Vectors are writeable views.");
  c.def(py::init<int>(), py::arg("dof"))
      .def("copy", [](const RobotCommand& command) { return RobotCommand(command); }, "A deep copy.")
      .def_readwrite("mode", &RobotCommand::mode);
  vector_property(c, "q_rad", &RobotCommand::q_rad, true, "Position set-point [rad] (kPosition).");
  vector_property(c, "tau_Nm", &RobotCommand::tau_Nm, true, "Torque set-point [N m] (Kinova torque loops, plain torque).");
  vector_property(c, "current_A", &RobotCommand::current_A, true, "Motor current set-point [A] (custom loop).");
}

}  // namespace

void bind_robot(py::module_& m) {
  bind_enum<LowLevelMode, kLowLevelModeCount>(m, "LowLevelMode",
                                              "Which actuator loop runs: position, kinova_torque, "
                                              "kinova_torque_high_velocity, custom (the paper's loop, drives in current mode), "
                                              "torque (a generic drive's plain torque).");
  py::enum_<WriteStatus>(m, "WriteStatus", "The answer of RobotInterface.write; anything but ok refused the command.")
      .value("ok", WriteStatus::kOk)
      .value("invalid_mode", WriteStatus::kInvalidMode)
      .value("size_mismatch", WriteStatus::kSizeMismatch)
      .value("not_finite", WriteStatus::kNotFinite)
      .value("out_of_range", WriteStatus::kOutOfRange)
      .value("fault", WriteStatus::kFault);
  bind_state(m);
  bind_command(m);
  py::class_<RobotInterface>(m, "RobotInterface", "The one boundary between the controller and an arm.")
      .def_property_readonly("dof", &RobotInterface::dof, "Number of joints.")
      .def_property_readonly("period_s", &RobotInterface::period_s, "Control period [s].")
      .def("read", &RobotInterface::read, py::return_value_policy::reference_internal,
           "The next state (the simulator advances one period). The returned state is the robot's own: its views "
           "show later reads too.")
      .def("write", &RobotInterface::write, py::arg("command"),
           "Validates and stores the command for the next cycle; a refusal changes nothing but the status.");
}

}  // namespace phri::python
