#include <phri/config/task_config.hpp>

#include <phri/control/constraint_registry.hpp>
#include <phri/control/task_registry.hpp>

namespace phri {
namespace {

// Numbers span every key a task reads (forces, stiffnesses, weights up to 1e8); the factories
// check each key's own range.
constexpr double kAnyNumber = 1e12;

TaskSpec parse_spec(const YamlReader& entry, void (*check_keys)(const TaskSpec&)) {
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
  check_keys(spec);
  return spec;
}

std::vector<TaskSpec> parse_specs(const YamlReader& list, void (*check_keys)(const TaskSpec&), const char* kind) {
  list.expect_sequence();
  std::vector<TaskSpec> specs;
  for (std::size_t i = 0; i < list.size(); ++i) {
    TaskSpec spec = parse_spec(list.at(i), check_keys);
    for (const TaskSpec& other : specs) {
      if (other.name == spec.name) spec.fail("name", std::string("a second ") + kind + " named '" + spec.name + "'");
    }
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace

std::vector<TaskSpec> parse_task_specs(const YamlReader& list) { return parse_specs(list, &check_task_keys, "task"); }
std::vector<TaskSpec> parse_constraint_specs(const YamlReader& list) {
  return parse_specs(list, &check_constraint_keys, "constraint");
}

}  // namespace phri
