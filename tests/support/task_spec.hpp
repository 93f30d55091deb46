#pragma once
// A TaskSpec as the run YAML's controller.tasks[i] gives it, for tests that build tasks.
#include <phri/control/task_spec.hpp>

#include <string>

namespace phri::test {

inline TaskSpec task_spec(const std::string& type, const std::string& name,
                          const std::string& source = "test.yaml: controller.tasks[0]") {
  TaskSpec s;
  s.type = type;
  s.name = name;
  s.source = source;
  return s;
}

}  // namespace phri::test
