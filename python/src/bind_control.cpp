// phri/control for Python: ControllerSettings, ControllerTargets (the one way in while running),
// and Controller, whose step(state, targets, command) is one control period:
//   controller = phri.Controller(phri.ControllerSettings())    # the shipped Gen3 files
//   targets = phri.ControllerTargets(7); command = phri.RobotCommand(7)
//   controller.step(robot.read(), targets, command); robot.write(command)
// Controller outputs (desired torque, external torque...) are read-only views updated every step.
#include "bindings.hpp"

#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>

namespace phri::python {
namespace {

void bind_control_enums(py::module_& m) {
  bind_enum<ComplianceMode, kComplianceModeCount>(m, "ComplianceMode",
                                                 "The paper's compliance modes: stiff, null_space, full_body, dual.");
  bind_enum<CycleStatus, 6>(m, "CycleStatus", "What a controller step did (ok, or why it held or braked).");
  bind_enum<WholeBodyQpStatus, 6>(m, "WholeBodyQpStatus", "Outcome of the whole-body QP in the last step.");
  bind_enum<SupervisorState, 3>(m, "SupervisorState", "Safety supervisor: normal, degraded, safe_stop.");
  bind_enum<SafetyFault, static_cast<int>(SafetyFault::kLast) + 1>(m, "SafetyFault",
                                                                  "Why a sample was implausible or a safe stop began.");
  py::enum_<ExternalTorqueSource>(m, "ExternalTorqueSource", "Where the QP's external joint torque comes from.")
      .value("observer", ExternalTorqueSource::kObserver, "momentum observer on the joint torque sensors")
      .value("force_torque_sensor", ExternalTorqueSource::kForceTorqueSensor, "J^T of the F/T sensor's wrench")
      .value("fused", ExternalTorqueSource::kFused, "observer + high-pass of J^T F/T");
}

void bind_settings(py::module_& m) {
  py::class_<ComplianceSettings>(m, "ComplianceSettings", "Gains of the compliance modes and the dual-compliance trigger.")
      .def(py::init<>())
      .def_readwrite("ee_position_stiffness", &ComplianceSettings::ee_position_stiffness)
      .def_readwrite("ee_orientation_stiffness", &ComplianceSettings::ee_orientation_stiffness)
      .def_readwrite("ee_weight", &ComplianceSettings::ee_weight)
      .def_readwrite("full_body_ee_stiffness", &ComplianceSettings::full_body_ee_stiffness)
      .def_readwrite("posture_stiffness", &ComplianceSettings::posture_stiffness)
      .def_readwrite("posture_damping", &ComplianceSettings::posture_damping)
      .def_readwrite("posture_weight", &ComplianceSettings::posture_weight)
      .def_readwrite("touch_threshold", &ComplianceSettings::touch_threshold, "Wrench norm that starts a touch.")
      .def_readwrite("release_threshold", &ComplianceSettings::release_threshold, "Wrench norm that ends it.")
      .def_readwrite("touched_ee_damping", &ComplianceSettings::touched_ee_damping)
      .def_readwrite("touched_posture_damping", &ComplianceSettings::touched_posture_damping);
  py::class_<CustomTorqueSettings>(m, "CustomTorqueSettings", "The paper's custom torque loop (lambda, K_I, theta...).")
      .def(py::init<>())
      .def_readwrite("transfer_gain", &CustomTorqueSettings::transfer_gain)
      .def_readwrite("integral_gain", &CustomTorqueSettings::integral_gain)
      .def_readwrite("integral_leak", &CustomTorqueSettings::integral_leak)
      .def_readwrite("integral_limit_fraction", &CustomTorqueSettings::integral_limit_fraction)
      .def_readwrite("friction_compensation", &CustomTorqueSettings::friction_compensation)
      .def_readwrite("rotor_inertia_compensation", &CustomTorqueSettings::rotor_inertia_compensation);
  using S = ControllerSettings;
  py::class_<S>(m, "ControllerSettings",
                "Everything Controller needs. From Python the robot defaults to the shipped Gen3 bundle "
                "(robots/kinova_gen3 in data_dir(): files, frames, F/T sensor and tool); the C++ defaults "
                "name no robot and carry no end of arm.")
      .def(py::init([] {
        S s;
        RobotBundle::from_folder(locate("robots/kinova_gen3")).apply_to(s);
        return s;
      }))
      .def_readwrite("urdf_path", &S::urdf_path)
      .def_readwrite("actuators_path", &S::actuators_path)
      .def_readwrite("collision_path", &S::collision_path, "Empty: no self-collision constraint.")
      .def_readwrite("end_effector_frame", &S::end_effector_frame)
      .def_readwrite("base_link", &S::base_link, "Empty: the URDF's root.")
      .def_readwrite("tip_link", &S::tip_link, "Empty: the end of the only moving branch.")
      .def_readwrite("locked_joints", &S::locked_joints, "URDF joints held at 0 (gripper fingers).")
      .def_readwrite("collision_yaml", &S::collision_yaml, "A collision model's text, in place of collision_path when set.")
      .def_readwrite("ft_sensor_mount", &S::ft_sensor_mount, "F/T measuring frame in the end-effector frame (4 x 4).")
      .def_readwrite("payloads", &S::payloads)
      .def_readwrite("period_s", &S::period_s)
      .def_readwrite("observer_gain", &S::observer_gain, "Momentum observer bandwidth K_O [rad/s].")
      .def_readwrite("external_torque_source", &S::external_torque_source)
      .def_readwrite("deadband_large_Nm", &S::deadband_large_Nm)
      .def_readwrite("deadband_small_Nm", &S::deadband_small_Nm)
      .def_readwrite("compliance", &S::compliance)
      .def_readwrite("wrench_trigger_filter_s", &S::wrench_trigger_filter_s)
      .def_readwrite("custom_torque", &S::custom_torque)
      .def_readwrite("initial_compliance", &S::initial_compliance)
      .def_readwrite("initial_loop", &S::initial_loop);
}

void bind_targets(py::module_& m) {
  py::class_<PoseReference>(m, "PoseReference", "End-effector reference: pose (4 x 4), twist and acceleration (world axes).")
      .def(py::init<>())
      .def_readwrite("pose", &PoseReference::pose)
      .def_readwrite("velocity", &PoseReference::velocity)
      .def_readwrite("acceleration", &PoseReference::acceleration);
  py::class_<PostureReference> posture(m, "PostureReference", "Joint-space reference of the posture task (writeable views).");
  auto vector = [&posture](const char* name, Eigen::VectorXd PostureReference::*member) {
    posture.def_property(
        name, [member](py::object self) { return vector_view(self.cast<PostureReference&>().*member, self, true); },
        [member, name](PostureReference& self, const Eigen::Ref<const Eigen::VectorXd>& v) { assign_same_size(self.*member, v, name); });
  };
  vector("q", &PostureReference::q);
  vector("qd", &PostureReference::qd);
  vector("qdd", &PostureReference::qdd);

  using T = ControllerTargets;
  py::class_<T>(m, "ControllerTargets",
                "Run-time changes as plain data: requests act once (the step they are given), references persist.")
      .def(py::init<int>(), py::arg("nv"))
      .def_readwrite("compliance_mode", &T::compliance_mode, "Switch to this compliance mode (None: no request).")
      .def_readwrite("low_level_mode", &T::low_level_mode, "Switch to this loop, bumplessly (None: no request).")
      .def_readwrite("stiffness_scale", &T::stiffness_scale, "End-effector stiffness factor, clamped to [0.1, 4].")
      .def_readwrite("has_pose", &T::has_pose, "`pose` is the end-effector task's new reference.")
      .def_readwrite("pose", &T::pose)
      .def_readwrite("has_posture", &T::has_posture, "`posture` is the posture task's new reference.")
      .def_readwrite("posture", &T::posture)
      .def("clear", &T::clear, "Nothing requested, no new reference (buffers kept).")
      .def("set_pose",
           [](T& t, const Eigen::Isometry3d& pose, const Vector6d& velocity, const Vector6d& acceleration) {
             t.pose = {pose, velocity, acceleration};
             t.has_pose = true;
           },
           py::arg("pose"), py::arg("velocity") = Vector6d::Zero(), py::arg("acceleration") = Vector6d::Zero(),
           "A new end-effector reference (4 x 4 pose, twist, acceleration).")
      .def("set_posture",
           [](T& t, const Eigen::Ref<const Eigen::VectorXd>& q, std::optional<Eigen::VectorXd> qd,
              std::optional<Eigen::VectorXd> qdd) {
             assign_same_size(t.posture.q, q, "ControllerTargets.set_posture q");
             if (qd) assign_same_size(t.posture.qd, *qd, "ControllerTargets.set_posture qd"); else t.posture.qd.setZero();
             if (qdd) assign_same_size(t.posture.qdd, *qdd, "ControllerTargets.set_posture qdd"); else t.posture.qdd.setZero();
             t.has_posture = true;
           },
           py::arg("q"), py::arg("qd") = py::none(), py::arg("qdd") = py::none(),
           "A new posture reference (qd, qdd default to zero); copied into the targets' own buffers.");
}

// Controller outputs as read-only views (owner: the controller).
template <class Getter>
void controller_view(py::class_<Controller>& c, const char* name, Getter getter, const char* doc) {
  c.def_property_readonly(name, [getter](py::object self) { return vector_view(getter(self.cast<const Controller&>()), self); }, doc);
}

void bind_controller_outputs(py::class_<Controller>& c) {
  controller_view(c, "external_torque", [](const Controller& k) -> const Eigen::VectorXd& { return k.external_torque(); },
                  "External joint torque the QP used [N m] (view).");
  controller_view(c, "desired_acceleration", [](const Controller& k) -> const Eigen::VectorXd& { return k.qp().desired_acceleration(); },
                  "QP's qdd_d [rad/s^2] (view).");
  controller_view(c, "desired_torque", [](const Controller& k) -> const Eigen::VectorXd& { return k.qp().desired_torque(); },
                  "tau_d = M qdd_d + h - tau_ext [N m] (view).");
  controller_view(c, "observer_torque", [](const Controller& k) -> const Eigen::VectorXd& { return k.observer().external_torque(); },
                  "Momentum observer's tau_ext [N m] (view).");
  c.def_property_readonly("ee_pose", [](const Controller& k) { return k.qp().end_effector().pose(); },
                          "End-effector pose from the controller's model (4 x 4 copy).")
      .def_property_readonly("ee_target_pose", [](const Controller& k) { return k.qp().end_effector().target_pose(); },
                             "Target the end-effector task tracks (4 x 4 copy).")
      .def_property_readonly("ee_error", [](const Controller& k) { return Vector6d(k.qp().end_effector().error()); },
                             "Target - pose: position [m]; log(R* R^T) [rad].")
      .def_property_readonly("posture_target", [](const Controller& k) { return Eigen::VectorXd(k.qp().posture().target()); },
                             "The posture task's target [rad] (copy).")
      .def_property_readonly("wrench_world", [](const Controller& k) { return Vector6d(k.wrench().wrench_world()); },
                             "Operator wrench at the end effector, world axes (F/T).")
      .def_property_readonly("compliance_mode", [](const Controller& k) { return k.compliance().mode(); })
      .def_property_readonly("touched", [](const Controller& k) { return k.compliance().touched(); },
                             "Dual compliance: the end effector is being touched.")
      .def_property_readonly("touch_count", [](const Controller& k) { return k.compliance().touch_count(); })
      .def_property_readonly("stiffness_scale", [](const Controller& k) { return k.compliance().stiffness_scale(); })
      .def_property_readonly("low_level_loop", [](const Controller& k) { return k.low_level().loop(); })
      .def_property_readonly("qp_status", [](const Controller& k) { return k.qp().status(); })
      .def_property_readonly("qp_iterations", [](const Controller& k) { return k.qp().qp_iterations(); })
      .def_property_readonly("supervisor_state", [](const Controller& k) { return k.supervisor().state(); })
      .def_property_readonly("sample_fault", [](const Controller& k) { return k.supervisor().sample_fault(); },
                             "Fault of this cycle's sample (none: plausible).");
}

void bind_controller(py::module_& m) {
  py::class_<Controller> c(m, "Controller",
                           "One control period of the paper's framework: observer, F/T, compliance, QP, inverse "
                           "dynamics, low level. step() allocates nothing and never throws.");
  c.def(py::init<const ControllerSettings&>(), py::arg("settings"), "Loads the settings' files; ConfigError on bad input.")
      .def("step", py::overload_cast<const RobotState&, const ControllerTargets&, RobotCommand&>(&Controller::step),
           py::arg("state"), py::arg("targets"), py::arg("command"),
           "One cycle: apply the targets, estimate, QP, inverse dynamics, low level; writes `command`.")
      .def("step", py::overload_cast<const RobotState&, RobotCommand&>(&Controller::step), py::arg("state"), py::arg("command"),
           "One cycle with no new targets.")
      .def("report_fault", &Controller::report_fault, py::arg("fault"), py::arg("time_s"),
           "A fault the caller found (e.g. a refused write): safe stop from the next step.")
      .def_property_readonly("model", &Controller::model, py::return_value_policy::reference_internal)
      .def_property_readonly("data", &Controller::data, py::return_value_policy::reference_internal,
                             "The controller's model terms of the last step (M, h, g as views).")
      .def_property_readonly("settings", [](const Controller& k) { return ControllerSettings(k.settings()); }, "A copy.")
      .def_property_readonly("status", &Controller::status)
      .def_property_readonly("held_cycles", &Controller::held_cycles)
      .def_property_readonly("rejected_targets", &Controller::rejected_targets)
      .def_property_readonly("started", &Controller::started)
      .def_property_readonly("holding", &Controller::holding, "The safe stop handed over to the position hold.")
      .def_property_readonly("end_effector_frame", &Controller::end_effector_frame)
      .def_property_readonly("sensor_frame", &Controller::sensor_frame)
      .def_property_readonly("trigger_wrench_norm", &Controller::trigger_wrench_norm);
  bind_controller_outputs(c);
}

}  // namespace

void bind_control(py::module_& m) {
  bind_control_enums(m);
  bind_settings(m);
  bind_targets(m);
  bind_controller(m);
}

}  // namespace phri::python
