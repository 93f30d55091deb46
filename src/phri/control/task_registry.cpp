#include <phri/control/task_registry.hpp>

#include <phri/core/format.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {

// ---- the registry: one line per type, X(name) for the function `name##_task_type()` in its file.
#define PHRI_TASK_TYPES(X) \
  X(pose)                  \
  X(posture)               \
  X(force)                 \
  X(frame)

#define PHRI_DECLARE_TASK_TYPE(name) const TaskType& name##_task_type();
PHRI_TASK_TYPES(PHRI_DECLARE_TASK_TYPE)
#undef PHRI_DECLARE_TASK_TYPE

std::span<const TaskType* const> task_types() {
#define PHRI_LIST_TASK_TYPE(name) &name##_task_type(),
  static const TaskType* const types[] = {PHRI_TASK_TYPES(PHRI_LIST_TASK_TYPE)};
#undef PHRI_LIST_TASK_TYPE
  return types;
}
#undef PHRI_TASK_TYPES

const TaskType* find_task_type(std::string_view name) {
  for (const TaskType* type : task_types()) {
    if (type->name == name) return type;
  }
  return nullptr;
}

namespace {
std::vector<std::string_view> type_names() {
  std::vector<std::string_view> names;
  for (const TaskType* type : task_types()) names.push_back(type->name);
  return names;
}
}  // namespace

void check_task_keys(const TaskSpec& spec) {
  const TaskType* type = find_task_type(spec.type);
  if (!type) spec.fail("type", "unknown task type '" + spec.type + "' (known: " + join_words(type_names()) + ")");
  spec.check_keys("task", type->keys);
}

std::unique_ptr<Task> make_task(const TaskSpec& spec, const TaskBuildContext& context) {
  check_task_keys(spec);
  if (spec.name.empty()) spec.fail("name", "every task needs a name");
  return find_task_type(spec.type)->make(spec, context);
}

// ---- TaskSpec readers
namespace {
const std::vector<double>* numbers_of(const TaskSpec& spec, std::string_view key) {
  const auto it = spec.numbers.find(key);
  if (it != spec.numbers.end()) return &it->second;
  if (spec.words.count(key)) spec.fail(std::string(key), "must be a number or a list of numbers");
  return nullptr;
}
void check_range(const TaskSpec& spec, std::string_view key, double v, double low, double high) {
  if (!std::isfinite(v) || v < low || v > high) {
    spec.fail(std::string(key), format_general(v, 6) + " is outside [" + format_general(low, 6) + ", " +
                                    format_general(high, 6) + "]");
  }
}
template <int N>
Eigen::Matrix<double, N, 1> fixed_list(const TaskSpec& spec, std::string_view key, const Eigen::Matrix<double, N, 1>& fallback,
                                       double low, double high) {
  const std::vector<double>* v = numbers_of(spec, key);
  if (!v) return fallback;
  if (v->size() != 1 && v->size() != static_cast<std::size_t>(N)) {
    spec.fail(std::string(key), "needs 1 or " + std::to_string(N) + " numbers, got " + std::to_string(v->size()));
  }
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; i < N; ++i) {
    out[i] = (*v)[v->size() == 1 ? 0 : static_cast<std::size_t>(i)];
    check_range(spec, key, out[i], low, high);
  }
  return out;
}
}  // namespace

double TaskSpec::number(std::string_view key, double fallback, double low, double high) const {
  const std::vector<double>* v = numbers_of(*this, key);
  if (!v) return fallback;
  if (v->size() != 1) fail(std::string(key), "needs one number");
  check_range(*this, key, v->front(), low, high);
  return v->front();
}
Vector6d TaskSpec::six(std::string_view key, const Vector6d& fallback, double low, double high) const {
  return fixed_list<6>(*this, key, fallback, low, high);
}
Eigen::Vector3d TaskSpec::three(std::string_view key, const Eigen::Vector3d& fallback, double low, double high) const {
  return fixed_list<3>(*this, key, fallback, low, high);
}
std::string TaskSpec::word(std::string_view key, const std::string& fallback, const std::vector<std::string>& choices) const {
  const auto it = words.find(key);
  if (it == words.end()) {
    if (numbers.count(key)) fail(std::string(key), "must be one of the words listed in docs/tasks.md");
    return fallback;
  }
  if (std::find(choices.begin(), choices.end(), it->second) == choices.end()) {
    std::string list;
    for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
    fail(std::string(key), "'" + it->second + "' is not one of: " + list);
  }
  return it->second;
}

void TaskSpec::check_keys(std::string_view kind, const std::vector<std::string_view>& keys) const {
  auto check = [&](const std::string& key) {
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
      fail(key, "unknown key for a " + type + " " + std::string(kind) + " (known: type, name, " + join_words(keys) + ")");
    }
  };
  for (const auto& [key, value] : numbers) check(key);
  for (const auto& [key, value] : words) check(key);
}

std::string join_words(const std::vector<std::string_view>& words) {
  std::string text;
  for (std::string_view w : words) text += (text.empty() ? "" : ", ") + std::string(w);
  return text;
}

ComplianceRole task_role(const TaskSpec& spec, ComplianceRole fallback) {
  const std::string fallback_word = fallback == ComplianceRole::kMain        ? "main"
                                    : fallback == ComplianceRole::kNullSpace ? "null_space"
                                                                             : "none";
  const std::string role = spec.word("role", fallback_word, {"main", "null_space", "none"});
  return role == "main" ? ComplianceRole::kMain : role == "null_space" ? ComplianceRole::kNullSpace : ComplianceRole::kNone;
}

int task_frame(const TaskSpec& spec, const TaskBuildContext& context, bool required) {
  const auto it = spec.words.find("frame");
  if (it == spec.words.end()) {
    if (required) spec.fail("frame", "name the frame (a link of the URDF, or end_effector)");
    return context.end_effector_frame;
  }
  if (it->second == "end_effector") return context.end_effector_frame;
  if (!context.model.has_frame(it->second)) spec.fail("frame", "no frame '" + it->second + "' in the robot's model");
  return context.model.frame_id(it->second);
}

// ---- pose and posture: the paper's two tasks, and pose tasks on other frames
namespace {
TaskAxes task_axes(const TaskSpec& spec) {
  return spec.word("axes", "world", {"world", "frame"}) == "world" ? TaskAxes::kWorld : TaskAxes::kFrame;
}

constexpr double kMaxStiffness = 1e4;   // [1/s^2]: a 10 ms time constant, beyond what a 1 kHz loop follows
constexpr double kMaxWeight = 1e8;

std::unique_ptr<Task> make_pose_task(const TaskSpec& spec, const TaskBuildContext& context) {
  if (spec.name == "end_effector") spec.fail("name", "the main task is configured by the paper's configuration, not built");
  const ComplianceRole role = task_role(spec, ComplianceRole::kNone);
  auto task = std::make_unique<EndEffectorTask>(context.model, task_frame(spec, context, true),
                                                context.smoothing_time_constant, TargetLimits{}, 0.0, spec.name, role);
  task->set_axes(task_axes(spec));
  task->set_selection(spec.six("selection", Vector6d::Ones(), 0.0, 1.0));
  const Vector6d stiffness = spec.six("stiffness", Vector6d::Constant(100.0), 0.0, kMaxStiffness);
  const Vector6d damping = spec.six("damping", 2.0 * stiffness.cwiseSqrt(), 0.0, 1e3);
  const Vector6d gamma = spec.six("gamma", Vector6d::Zero(), 0.0, 1.0);
  task->reset_gains(stiffness, damping, spec.number("weight", 100.0, 0.0, kMaxWeight), gamma);
  if (role == ComplianceRole::kNone || spec.has("gamma")) task->set_fixed_gamma(gamma);
  return task;
}

std::unique_ptr<Task> make_posture_task(const TaskSpec& spec, const TaskBuildContext&) {
  spec.fail("type", "the posture is the paper's null-space task: configure it under the name 'posture'");
}
}  // namespace

const TaskType& pose_task_type() {
  static const TaskType type{"pose", "a frame's pose (position and orientation)",
                             {"frame", "axes", "selection", "stiffness", "damping", "weight", "gamma", "role"},
                             &make_pose_task};
  return type;
}
const TaskType& posture_task_type() {
  static const TaskType type{"posture", "the joint posture (the paper's null-space task)", {"gamma"}, &make_posture_task};
  return type;
}

std::optional<Vector6d> configure_main_task(const TaskSpec& spec, EndEffectorTask& task) {
  check_task_keys(spec);
  if (spec.type != "pose") spec.fail("type", "the end_effector task is a pose task");
  for (const char* key : {"frame", "damping", "weight", "role"}) {
    if (spec.has(key)) {
      spec.fail(key, "the main task's is the robot's (frame) or the compliance settings' (controller.compliance)");
    }
  }
  task.set_axes(task_axes(spec));
  task.set_selection(spec.six("selection", Vector6d::Ones(), 0.0, 1.0));
  if (spec.has("gamma")) task.set_fixed_gamma(spec.six("gamma", Vector6d::Zero(), 0.0, 1.0));
  if (!spec.has("stiffness")) return std::nullopt;
  return spec.six("stiffness", Vector6d::Zero(), 0.0, kMaxStiffness);
}

void configure_posture_task(const TaskSpec& spec, PostureTask& task) {
  check_task_keys(spec);
  if (spec.type != "posture") spec.fail("type", "the posture task is of type posture");
  if (spec.has("gamma")) task.set_fixed_gamma(spec.number("gamma", 0.0, 0.0, 1.0));
}

}  // namespace phri
