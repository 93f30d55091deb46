#include <phri/config/task_config.hpp>

#include <phri/control/task_registry.hpp>

namespace phri {
namespace {

// Numbers span every key a task reads (forces, stiffnesses, weights up to 1e8); the factories
// check each key's own range.
constexpr double kAnyNumber = 1e12;

TaskSpec parse_task_spec(const YamlReader& entry) {
  entry.expect_map();
  TaskSpec spec;
  spec.source = entry.file();
  spec.path = entry.path();
  spec.type = entry.text("type");
  spec.name = entry.text("name");
  for (const std::string& key : entry.keys()) {
    if (key == "type" || key == "name") continue;
    const YamlReader value = entry.at(key);
    if (value.is_sequence()) {
      std::vector<double>& numbers = spec.numbers[key];
      for (std::size_t i = 0; i < value.size(); ++i) numbers.push_back(value.at(i).as_number(-kAnyNumber, kAnyNumber));
      if (numbers.empty()) throw entry.error(key, "an empty list");
    } else if (value.is_map()) {
      throw entry.error(key, "must be a number, a list of numbers or a word");
    } else {
      const std::string text = value.as_text();
      try {
        spec.numbers[key] = {value.as_number(-kAnyNumber, kAnyNumber)};
      } catch (const ConfigError&) {
        spec.words[key] = text;
      }
    }
  }
  check_task_keys(spec);
  return spec;
}

}  // namespace

std::vector<TaskSpec> parse_task_specs(const YamlReader& list) {
  list.expect_sequence();
  std::vector<TaskSpec> specs;
  for (std::size_t i = 0; i < list.size(); ++i) {
    TaskSpec spec = parse_task_spec(list.at(i));
    for (const TaskSpec& other : specs) {
      if (other.name == spec.name) spec.fail("name", "a second task named '" + spec.name + "'");
    }
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace phri
