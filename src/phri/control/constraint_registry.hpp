#pragma once
// The constraint types a run can add (`controller.constraints:` in the run YAML), by name. A type
// is a factory in its own file plus one line in constraint_registry.cpp's list (docs/tasks.md).
// The paper's safety constraints (velocity, joint limits, torque, self-collision) are always on:
// the supervisor and the fallback rely on them; `controller.qp` tunes them.
//
//   plane    a frame's origin kept on one side of a plane (plane_constraint.cpp)
#include <phri/control/constraint.hpp>
#include <phri/control/task_spec.hpp>

#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace phri {

/// A declared constraint is plain data of the same form as a declared task.
using ConstraintSpec = TaskSpec;

/// What a factory may read besides its spec.
struct ConstraintBuildContext {
  const Model& model;
  int end_effector_frame;  ///< the robot's end-effector frame id
};

struct ConstraintType {
  std::string_view name;
  std::string_view summary;
  std::vector<std::string_view> keys;  ///< the keys a spec of this type may have (besides type, name)
  std::unique_ptr<Constraint> (*make)(const ConstraintSpec& spec, const ConstraintBuildContext& context);
};

/// Every registered type, in the registry's order.
std::span<const ConstraintType* const> constraint_types();
/// The type of that name, or null.
const ConstraintType* find_constraint_type(std::string_view name);
/// Checks a spec's type and keys (ConfigError naming spec.source and the first unknown key).
void check_constraint_keys(const ConstraintSpec& spec);
/// Builds a constraint from its spec: ConfigError (naming spec.source and the key) for an unknown
/// type, an unknown key or a bad value.
std::unique_ptr<Constraint> make_constraint(const ConstraintSpec& spec, const ConstraintBuildContext& context);

}  // namespace phri
