#pragma once
// The task types a run can declare (`controller.tasks:` in the run YAML), by name. A type is a
// factory in its own file plus one line in task_registry.cpp's list (see docs/tasks.md).
//
//   pose     a frame's pose (the main task is the end effector's, paper eq. compliantQP)
//   posture  the joint posture (the paper's null-space task)
//   force    a contact force along an axis at the end effector (force_task.cpp)
//   frame    a link's position along chosen world axes (frame_task.cpp)
#include <phri/control/end_effector_task.hpp>
#include <phri/control/posture_task.hpp>
#include <phri/control/task.hpp>
#include <phri/control/task_spec.hpp>

#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace phri {

/// What a factory may read besides its spec.
struct TaskBuildContext {
  const Model& model;
  int end_effector_frame;          ///< the robot's end-effector frame id
  double smoothing_time_constant;  ///< of the tasks' gain filters [s]
};

struct TaskType {
  std::string_view name;
  std::string_view summary;
  std::vector<std::string_view> keys;  ///< the keys a spec of this type may have (besides type, name)
  std::unique_ptr<Task> (*make)(const TaskSpec& spec, const TaskBuildContext& context);
};

/// Every registered type, in the registry's order.
std::span<const TaskType* const> task_types();
/// The type of that name, or null.
const TaskType* find_task_type(std::string_view name);
/// Builds a task from its spec: ConfigError (naming spec.source and the key) for an unknown type,
/// an unknown key or a bad value.
std::unique_ptr<Task> make_task(const TaskSpec& spec, const TaskBuildContext& context);
/// Checks a spec's keys against its type's (ConfigError naming the first unknown key).
void check_task_keys(const TaskSpec& spec);

/// The paper's two tasks, configured by the specs named "end_effector" (type pose) and "posture":
/// axes, selection, a fixed gamma; the main task's per-axis stiffness goes to the compliance
/// settings (returned, empty when the spec gives none).
std::optional<Vector6d> configure_main_task(const TaskSpec& spec, EndEffectorTask& task);
void configure_posture_task(const TaskSpec& spec, PostureTask& task);

// Readers shared by the factories.
ComplianceRole task_role(const TaskSpec& spec, ComplianceRole fallback);
/// A frame of the model by name; "end_effector" (or no key) is the robot's end-effector frame.
int task_frame(const TaskSpec& spec, const TaskBuildContext& context, bool required);

}  // namespace phri
