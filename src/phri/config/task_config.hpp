#pragma once
// The run YAML's `controller.tasks:` list -> TaskSpec (control/task_spec.hpp). Each entry is a map
// with `type` and `name`; its other keys are numbers, lists of numbers or words, checked against
// the type's keys (control/task_registry.hpp) at load: an unknown type or key is a ConfigError
// naming it ("controller.tasks[2].forse_N"). Values are checked when the controller builds the task.
#include <phri/control/task_spec.hpp>
#include <phri/core/yaml_reader.hpp>

#include <vector>

namespace phri {

std::vector<TaskSpec> parse_task_specs(const YamlReader& list);
/// `controller.constraints:`, the same form, checked against the constraint types
/// (control/constraint_registry.hpp).
std::vector<TaskSpec> parse_constraint_specs(const YamlReader& list);

}  // namespace phri
