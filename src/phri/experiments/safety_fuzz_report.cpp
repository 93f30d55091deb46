// The safety-fuzz experiment's outputs: the CSV of every window, the Markdown report and the command.
#include <phri/experiments/safety_fuzz.hpp>

#include <phri/core/format.hpp>
#include <phri/experiments/experiment_files.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <ostream>
#include <sstream>
#include <tuple>

namespace phri {
namespace {

bool is_push(const FuzzRecord& r) {
  return r.kind == FuzzCaseKind::kRandomPush || r.kind == FuzzCaseKind::kLimitPush || r.kind == FuzzCaseKind::kWristFold;
}

std::string violation_list(unsigned bits) {
  std::string s;
  for (int i = 0; i < kFuzzViolationCount; ++i) {
    if ((bits & (1u << i)) == 0) continue;
    if (!s.empty()) s += '+';
    s += violation_name(i);
  }
  return s;
}

std::string number(double x, int digits) { return std::isfinite(x) ? format_fixed(x, digits) : (x > 0 ? "inf" : "-inf"); }

// How bad a failing window is, to list the worst first: a crash, a NaN command or an unhandled
// refusal first, then contact and limits by depth, speed by its ratio, then recovery.
double severity(const FuzzRecord& r) {
  const WindowMetrics& m = r.metrics;
  const unsigned v = r.verdict.violations;
  double s = 0.0;
  if (v & (kViolationCrash | kViolationNanCommand | kViolationUnhandledRefusal)) s += 100.0;
  if (v & kViolationCollision) s += 20.0 + 1e3 * std::max(0.0, -m.min_capsule_distance_m);
  if (v & kViolationJointLimit) s += 20.0 + 180.0 / std::numbers::pi * std::max(0.0, -m.min_limit_margin_rad);
  if (v & kViolationOverspeed) s += 10.0 * m.max_speed_ratio;
  if (v & (kViolationNoRecovery | kViolationSafeStopMoving)) s += 5.0 + std::min(m.max_deviation_rad, 5.0);
  if (v & kViolationRefusedWrite) s += 3.0;
  return s;
}

std::string what(const FuzzRecord& r) {
  std::ostringstream s;
  if (is_push(r)) {
    s << format_fixed(r.force_N, 0) << " N " << r.profile << " " << format_fixed(r.duration_s, 2) << " s on " << r.target;
    if (r.kind == FuzzCaseKind::kLimitPush) s << " (joint " << r.joint + 1 << ")";
  } else if (r.kind == FuzzCaseKind::kFault) {
    s << r.target << " x" << r.fault_cycles;
    if (r.joint >= 0) s << " (joint " << r.joint + 1 << ")";
    if (r.context == "motion" || r.context == "switch") {
      s << " " << format_fixed(r.fault_offset_s, 3) << " s after " << (r.context == "switch" ? "the loop switch in " : "the start of ")
        << format_fixed(r.force_N, 0) << " N " << r.profile << " " << format_fixed(r.duration_s, 2) << " s on " << r.push_link;
    }
  } else if (r.context == "motion" || r.context == "switch") {
    s << r.context << " reference: " << format_fixed(r.force_N, 0) << " N " << r.profile << " " << format_fixed(r.duration_s, 2)
      << " s on " << r.push_link;
  } else {
    s << to_string(r.kind);
  }
  if (!r.error.empty()) s << ": " << r.error;
  return s.str();
}

std::string replay_command(const FuzzRecord& r, const SafetyFuzzOptions& o) {
  std::string c = "phri experiment safety-fuzz --seed " + std::to_string(o.seed) + " --pushes " + std::to_string(o.pushes);
  if (o.pushes_per_run != SafetyFuzzOptions{}.pushes_per_run) c += " --pushes-per-run " + std::to_string(o.pushes_per_run);
  if (!o.robot_folder.empty()) c += " --robot " + o.robot_folder;
  return c + " --replay " + r.run_id;
}

// Counts of one mode x loop pair.
struct PairCounts {
  long pushes = 0, push_violations = 0, operator_possible = 0, push_failures = 0, push_safe_stops = 0, no_recovery = 0;
  long faults = 0, fault_failures = 0, fault_safe_stops = 0, other_failures = 0, invalid = 0;

  void add(const FuzzRecord& r) {
    const bool failure = r.verdict.controller_failure();
    invalid += r.verdict.invalid;
    if (is_push(r)) {
      ++pushes;
      push_violations += r.verdict.violations != 0;
      operator_possible += r.verdict.violations != 0 && r.verdict.operator_possible;
      push_failures += failure;
      push_safe_stops += r.metrics.safe_stop;
      no_recovery += (r.verdict.violations & kViolationNoRecovery) != 0;
    } else if (r.kind == FuzzCaseKind::kFault) {
      ++faults;
      fault_failures += failure;
      fault_safe_stops += r.metrics.safe_stop;
    } else {
      other_failures += failure;
    }
  }
};

void pair_table(const SafetyFuzzResult& result, std::ostream& s) {
  std::map<std::pair<int, int>, PairCounts> pairs;
  for (const FuzzRecord& r : result.records) pairs[{static_cast<int>(r.mode), static_cast<int>(r.loop)}].add(r);
  s << "## Per compliance mode x low-level loop\n\n"
       "| mode | loop | pushes | with violations | operator-possible | controller failures | safe stops | not recovered | "
       "faults | fault failures | fault safe stops | start-up/reference failures | invalid windows |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [key, c] : pairs) {
    s << "| " << to_string(static_cast<ComplianceMode>(key.first)) << " | " << to_string(static_cast<LowLevelMode>(key.second))
      << " | " << c.pushes << " | " << c.push_violations << " | " << c.operator_possible << " | " << c.push_failures << " | "
      << c.push_safe_stops << " | " << c.no_recovery << " | " << c.faults << " | " << c.fault_failures << " | "
      << c.fault_safe_stops << " | " << c.other_failures << " | " << c.invalid << " |\n";
  }
  s << "\n";
}

std::string loop_list(const std::vector<LowLevelMode>& loops) {
  std::string out;
  for (LowLevelMode loop : loops) out += (out.empty() ? "" : ", ") + std::string(to_string(loop));
  return out;
}

// What the loop or mode under test ran as instead, e.g. "loop position instead of kinova_torque".
std::string off_intent(const FuzzRecord& r) {
  std::string out;
  if (r.metrics.ran_loop >= 0 && r.metrics.ran_loop != static_cast<int>(r.loop)) {
    out += "loop " + std::string(to_string(static_cast<LowLevelMode>(r.metrics.ran_loop))) + " instead of " +
           std::string(to_string(r.loop));
  }
  if (r.metrics.ran_mode >= 0 && r.metrics.ran_mode != static_cast<int>(r.mode)) {
    out += (out.empty() ? "" : ", ") + std::string("mode ") +
           std::string(to_string(static_cast<ComplianceMode>(r.metrics.ran_mode))) + " instead of " + std::string(to_string(r.mode));
  }
  return out.empty() ? "the loop under test not running after the switch" : out;
}

// The rows not run (the drive does not offer their loop) and the windows whose loop or mode did
// not run: neither is a pass.
void validity_section(const SafetyFuzzResult& result, std::ostream& s) {
  s << "## Skipped rows and invalid windows\n\n";
  if (result.skipped_loops.empty()) {
    s << "No row skipped: the drive offers every loop asked for.\n";
  } else {
    s << result.skipped_rows << " mode x loop rows skipped (not run, not counted): the drive does not offer " << loop_list(result.skipped_loops)
      << ".\n";
  }
  s << "\n" << result.invalid_windows() << " invalid windows (the loop or compliance mode under test was not the one running "
    << "before any safe stop: Controller::low_level().loop(), compliance().mode()); never counted as passes.\n\n";
  int listed = 0;
  for (const FuzzRecord& r : result.records) {
    if (!r.verdict.invalid || listed++ >= 20) continue;
    s << "- `" << r.run_id << "` #" << r.index << " " << to_string(r.kind) << ": " << off_intent(r) << " for "
      << r.metrics.off_intent_cycles << " cycles\n";
  }
  s << "\n";
}

void category_table(const SafetyFuzzResult& result, std::ostream& s) {
  const FuzzCaseKind kinds[] = {FuzzCaseKind::kRandomPush, FuzzCaseKind::kLimitPush, FuzzCaseKind::kWristFold,
                                FuzzCaseKind::kFault, FuzzCaseKind::kReference, FuzzCaseKind::kStartup};
  s << "## Controller failures by category\n\nA window counts once in each category it violates "
       "(operator-possible windows excluded).\n\n| category |";
  for (FuzzCaseKind k : kinds) s << " " << to_string(k) << " |";
  s << " total |\n|---|---|---|---|---|---|---|---|\n";
  for (int i = 0; i < kFuzzViolationCount; ++i) {
    long counts[6] = {0, 0, 0, 0, 0, 0}, total = 0;
    for (const FuzzRecord& r : result.records) {
      if (!r.verdict.controller_failure() || (r.verdict.violations & (1u << i)) == 0) continue;
      ++counts[static_cast<int>(r.kind)];
      ++total;
    }
    s << "| " << violation_name(i) << " |";
    for (FuzzCaseKind k : kinds) s << " " << counts[static_cast<int>(k)] << " |";
    s << " " << total << " |\n";
  }
  s << "\n";
}

void fault_table(const SafetyFuzzResult& result, std::ostream& s) {
  struct Row {
    long runs = 0, failures = 0, safe_stops = 0;
    unsigned categories = 0;
    std::string where;
  };
  std::map<std::tuple<std::string, std::string, long>, Row> rows;
  for (const FuzzRecord& r : result.records) {
    if (r.kind != FuzzCaseKind::kFault) continue;
    Row& row = rows[{r.context, r.target, r.fault_cycles}];
    ++row.runs;
    row.safe_stops += r.metrics.safe_stop;
    if (!r.verdict.controller_failure()) continue;
    ++row.failures;
    row.categories |= r.verdict.violations;
    row.where += (row.where.empty() ? "" : ", ") + std::string(to_string(r.mode)) + "/" + std::string(to_string(r.loop));
  }
  if (rows.empty()) return;
  s << "## Sensor faults\n\n| when | fault | cycles | runs | safe stops | controller failures | categories | where |\n"
       "|---|---|---|---|---|---|---|---|\n";
  for (const auto& [key, row] : rows) {
    s << "| " << std::get<0>(key) << " | " << std::get<1>(key) << " | " << std::get<2>(key) << " | " << row.runs << " | " << row.safe_stops << " | " << row.failures
      << " | " << violation_list(row.categories) << " | " << row.where << " |\n";
  }
  s << "\n";
}

// Every fault kind (catalogue entry) at rest, in motion and after a loop switch: windows, controller
// failures, safe stops; then the same by the decorator's kind.
void fault_kind_table(const SafetyFuzzResult& result, const SafetyFuzzOptions& o, std::ostream& s) {
  struct Cell {
    long windows = 0, failures = 0, safe_stops = 0;
  };
  struct Row {
    Cell cells[3];
    unsigned categories = 0;
  };
  std::map<std::string, Row> by_name, by_kind;
  std::map<std::string, std::string> kind_of;
  long totals[3] = {0, 0, 0}, failures[3] = {0, 0, 0};
  for (const FuzzRecord& r : result.records) {
    if (r.kind != FuzzCaseKind::kFault) continue;
    const int c = r.context == "motion" ? 1 : r.context == "switch" ? 2 : 0;
    kind_of[r.target] = r.fault_kind;
    for (Row* row : {&by_name[r.target], &by_kind[r.fault_kind]}) {
      ++row->cells[c].windows;
      row->cells[c].safe_stops += r.metrics.safe_stop;
      if (r.verdict.controller_failure()) {
        ++row->cells[c].failures;
        row->categories |= r.verdict.violations;
      }
    }
    ++totals[c];
    failures[c] += r.verdict.controller_failure();
  }
  if (by_name.empty()) return;
  auto cell = [](const Cell& x) {
    return x.windows == 0 ? std::string("-")
                          : std::to_string(x.failures) + " / " + std::to_string(x.windows) + " (" + std::to_string(x.safe_stops) + ")";
  };
  s << "## Sensor faults by kind, at rest and in motion\n\nController failures / windows (safe stops) per fault, at rest ("
    << failures[0] << " / " << totals[0] << "), during a push (" << failures[1] << " / " << totals[1]
    << ") and 0-" << format_fixed(1e3 * o.motion.max_switch_delay_s, 0)
    << " ms after the sample a loop switch took effect on, on a pushed arm (" << failures[2] << " / " << totals[2] << ").\n\n"
    << "| fault | kind | at rest | in motion | after a loop switch | categories |\n|---|---|---|---|---|---|\n";
  for (const auto& [name, row] : by_name) {
    s << "| " << name << " | " << kind_of[name];
    for (const Cell& c : row.cells) s << " | " << cell(c);
    s << " | " << violation_list(row.categories) << " |\n";
  }
  s << "\n| decorator kind | at rest | in motion | after a loop switch | categories |\n|---|---|---|---|---|\n";
  for (const auto& [kind, row] : by_kind) {
    s << "| " << kind;
    for (const Cell& c : row.cells) s << " | " << cell(c);
    s << " | " << violation_list(row.categories) << " |\n";
  }
  s << "\n";
}

// The windows that did not come back: where the arm ended (deviation from its reference when the
// window closed, the joint furthest off) and whether it had come to rest there.
void no_recovery_table(const SafetyFuzzResult& result, std::ostream& s) {
  std::map<std::pair<int, int>, std::vector<const FuzzRecord*>> pairs;
  for (const FuzzRecord& r : result.records) {
    if (r.verdict.controller_failure() && (r.verdict.violations & kViolationNoRecovery)) {
      pairs[{static_cast<int>(r.mode), static_cast<int>(r.loop)}].push_back(&r);
    }
  }
  if (pairs.empty()) return;
  s << "## Not recovered: where the arm ended\n\nFinal deviation from the reference when the window closed (3 s after "
       "the push or fault, plus the walk back), the joints furthest off (count), and how many had come to rest (max abs(qd) < 0.01 rad/s).\n\n"
       "| mode | loop | windows | final deviation median / p90 / max rad | joints furthest off | at rest |\n"
       "|---|---|---|---|---|---|\n";
  for (const auto& [key, list] : pairs) {
    std::vector<double> d;
    std::map<int, int> joints;
    long at_rest = 0;
    for (const FuzzRecord* r : list) {
      d.push_back(r->metrics.final_deviation_rad);
      ++joints[r->metrics.final_deviation_joint + 1];
      at_rest += r->metrics.final_speed_rad_s < 0.01;
    }
    std::sort(d.begin(), d.end());
    auto at = [&](double f) { return d[static_cast<std::size_t>(std::lround(f * static_cast<double>(d.size() - 1)))]; };
    s << "| " << to_string(static_cast<ComplianceMode>(key.first)) << " | " << to_string(static_cast<LowLevelMode>(key.second))
      << " | " << list.size() << " | " << number(at(0.5), 3) << " / " << number(at(0.9), 3) << " / " << number(d.back(), 3)
      << " |";
    for (const auto& [joint, n] : joints) {
      if (joint > 0) s << " j" << joint << ": " << n;  // 0: dual compliance, judged at rest only
    }
    s << " | " << at_rest << " |\n";
  }
  s << "\n";
}

template <typename Better>
const FuzzRecord* worst(const SafetyFuzzResult& result, bool failures_only, Better better) {
  const FuzzRecord* w = nullptr;
  for (const FuzzRecord& r : result.records) {
    if (failures_only && r.verdict.operator_possible) continue;
    if (w == nullptr || better(r, *w)) w = &r;
  }
  return w;
}

void margins(const SafetyFuzzResult& result, std::ostream& s) {
  s << "## Worst margins\n\n| margin | all windows | windows not operator-possible |\n|---|---|---|\n";
  auto cell = [](const FuzzRecord* r, double value, int digits, const char* unit) {
    if (r == nullptr) return std::string("-");
    return number(value, digits) + " " + unit + " (`" + r->run_id + "` #" + std::to_string(r->index) + ", " + what(*r) + ")";
  };
  const auto speed = [](const FuzzRecord& a, const FuzzRecord& b) { return a.metrics.max_speed_ratio > b.metrics.max_speed_ratio; };
  const auto limit = [](const FuzzRecord& a, const FuzzRecord& b) { return a.metrics.min_limit_margin_rad < b.metrics.min_limit_margin_rad; };
  const auto capsule = [](const FuzzRecord& a, const FuzzRecord& b) {
    return a.metrics.min_capsule_distance_m < b.metrics.min_capsule_distance_m;
  };
  const FuzzRecord* rows[3][2] = {{worst(result, false, speed), worst(result, true, speed)},
                                  {worst(result, false, limit), worst(result, true, limit)},
                                  {worst(result, false, capsule), worst(result, true, capsule)}};
  const char* names[3] = {"max abs(qd) / velocity limit", "joint-limit margin (< 0: penetration)", "smallest capsule distance"};
  for (int k = 0; k < 3; ++k) {
    s << "| " << names[k] << " |";
    for (int j = 0; j < 2; ++j) {
      const FuzzRecord* r = rows[k][j];
      const double v = r == nullptr ? 0.0
                       : k == 0     ? r->metrics.max_speed_ratio
                       : k == 1     ? r->metrics.min_limit_margin_rad * 180.0 / std::numbers::pi
                                    : 1e3 * r->metrics.min_capsule_distance_m;
      s << " " << cell(r, v, k == 0 ? 3 : 2, k == 0 ? "" : k == 1 ? "deg" : "mm") << " |";
    }
    s << "\n";
  }
  s << "\n";
}

std::vector<const FuzzRecord*> failures_worst_first(const SafetyFuzzResult& result) {
  std::vector<const FuzzRecord*> f;
  for (const FuzzRecord& r : result.records) {
    if (r.verdict.controller_failure()) f.push_back(&r);
  }
  std::stable_sort(f.begin(), f.end(), [](const FuzzRecord* a, const FuzzRecord* b) { return severity(*a) > severity(*b); });
  return f;
}

// Overspeeds on a held command (FuzzVerdict::held_command): not controller failures, never passes.
void held_command_list(const SafetyFuzzResult& result, const SafetyFuzzOptions& o, std::ostream& s) {
  std::vector<const FuzzRecord*> held;
  for (const FuzzRecord& r : result.records) {
    if (r.verdict.held_command) held.push_back(&r);
  }
  if (held.empty()) return;
  std::sort(held.begin(), held.end(),
            [](const FuzzRecord* a, const FuzzRecord* b) { return a->metrics.max_speed_ratio > b->metrics.max_speed_ratio; });
  s << "## Overspeed on a held command\n\n"
    << held.size() << " windows went over the speed threshold only while the robot ran on a command the controller could "
       "not renew (its thread stalled, its writes refused: the simulated robot keeps its last command, as most do), and the "
       "controller, acting again, never exceeded what it inherited and brought the arm back within the threshold. No "
       "controller acts while its thread is stalled; a robot whose own watchdog stops on missed commands ends these "
       "earlier. Not controller failures, not passes.\n\n"
    << "| run | mode | loop | what | max qd/limit held / inherited / controlled | safe stop | replay |\n"
       "|---|---|---|---|---|---|---|\n";
  for (const FuzzRecord* r : held) {
    const WindowMetrics& m = r->metrics;
    s << "| `" << r->run_id << "` | " << to_string(r->mode) << " | " << to_string(r->loop) << " | " << what(*r) << " | "
      << number(m.max_held_speed_ratio, 3) << " / " << number(m.max_inherited_speed_ratio, 3) << " / "
      << number(m.max_controlled_speed_ratio, 3) << " | " << (m.safe_stop ? r->safe_stop_reason : "-") << " | `"
      << replay_command(*r, o) << "` |\n";
  }
  s << "\n";
}

void failure_list(const SafetyFuzzResult& result, const SafetyFuzzOptions& o, std::ostream& s) {
  const std::vector<const FuzzRecord*> f = failures_worst_first(result);
  constexpr std::size_t kMaxRows = 200;
  s << "## Controller failures, worst first\n\n";
  if (f.empty()) {
    s << "None.\n";
    return;
  }
  if (f.size() > kMaxRows) s << "The " << kMaxRows << " worst of " << f.size() << " (all in safety_fuzz.csv).\n\n";
  s << "| # | run | window | mode | loop | what | violations | max qd/limit | limit margin deg | capsule mm | deviation max / final rad | "
       "safe stop | replay |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < std::min(f.size(), kMaxRows); ++i) {
    const FuzzRecord& r = *f[i];
    const WindowMetrics& m = r.metrics;
    s << "| " << i + 1 << " | `" << r.run_id << "` | " << r.index << " | " << to_string(r.mode) << " | " << to_string(r.loop)
      << " | " << what(r) << " | " << violation_list(r.verdict.violations) << " | " << number(m.max_speed_ratio, 3) << " | "
      << number(m.min_limit_margin_rad * 180.0 / std::numbers::pi, 2) << " | " << number(1e3 * m.min_capsule_distance_m, 1)
      << " | " << number(m.max_deviation_rad, 3)  << " / " << number(m.final_deviation_rad, 3)
      << (m.final_deviation_joint >= 0 ? " (j" + std::to_string(m.final_deviation_joint + 1) + ")" : std::string()) << " | " << (m.safe_stop ? r.safe_stop_reason : "-") << " | `"
      << replay_command(r, o) << "` |\n";
  }
}

}  // namespace

std::string safety_fuzz_csv(const SafetyFuzzResult& result) {
  std::ostringstream s;
  s << "run_id,index,kind,mode,loop,plant_seed,start_s,target,joint,force_N,profile,duration_s,fault_cycles,"
       "max_speed_ratio,min_limit_margin_rad,min_capsule_distance_mm,required_torque_ratio,max_deviation_rad,final_deviation_rad,final_deviation_joint,final_speed_rad_s,"
       "recovery_time_s,safe_stop,safe_stop_reason,safe_stop_rest_time_s,refused_writes,unhandled_refusals,nan_command,"
       "crashed,violations,operator_possible,controller_failure,context,fault_kind,push_link,fault_offset_s,error,invalid,"
       "ran_loop,ran_mode,held_command,max_held_speed_ratio,max_inherited_speed_ratio,max_controlled_speed_ratio\n";
  for (const FuzzRecord& r : result.records) {
    const WindowMetrics& m = r.metrics;
    std::string error = r.error;
    std::replace(error.begin(), error.end(), ',', ';');
    s << r.run_id << ',' << r.index << ',' << to_string(r.kind) << ',' << to_string(r.mode) << ',' << to_string(r.loop) << ','
      << r.plant_seed << ',' << format_fixed(r.start_s, 3) << ',' << r.target << ',' << (r.joint >= 0 ? r.joint + 1 : 0) << ','
      << format_fixed(r.force_N, 2) << ',' << r.profile << ',' << format_fixed(r.duration_s, 3) << ',' << r.fault_cycles << ','
      << number(m.max_speed_ratio, 4) << ',' << number(m.min_limit_margin_rad, 5) << ','
      << number(1e3 * m.min_capsule_distance_m, 2) << ',' << number(m.max_required_torque_ratio, 3) << ','
      << number(m.max_deviation_rad, 4) << ',' << number(m.final_deviation_rad, 4) << ','
      << m.final_deviation_joint + 1 << ',' << number(m.final_speed_rad_s, 4) << ',' << number(m.recovery_time_s, 3) << ',' << (m.safe_stop ? 1 : 0) << ','
      << r.safe_stop_reason << ',' << number(m.safe_stop_rest_time_s, 3) << ',' << m.refused_writes << ','
      << m.unhandled_refusals << ',' << (m.nan_command ? 1 : 0) << ',' << (m.crashed ? 1 : 0) << ','
      << violation_list(r.verdict.violations) << ',' << (r.verdict.operator_possible ? 1 : 0) << ','
      << (r.verdict.controller_failure() ? 1 : 0) << ',' << r.context << ',' << r.fault_kind << ',' << r.push_link << ','
      << format_fixed(r.fault_offset_s, 3) << ',' << error << ',' << (r.verdict.invalid ? 1 : 0) << ','
      << (m.ran_loop >= 0 ? to_string(static_cast<LowLevelMode>(m.ran_loop)) : std::string_view()) << ','
      << (m.ran_mode >= 0 ? to_string(static_cast<ComplianceMode>(m.ran_mode)) : std::string_view()) << ','
      << (r.verdict.held_command ? 1 : 0) << ',' << number(m.max_held_speed_ratio, 4) << ','
      << number(m.max_inherited_speed_ratio, 4) << ',' << number(m.max_controlled_speed_ratio, 4) << '\n';
  }
  return s.str();
}

std::string safety_fuzz_report(const SafetyFuzzResult& result, const SafetyFuzzOptions& o) {
  std::ostringstream s;
  long kinds[6] = {0, 0, 0, 0, 0, 0};
  for (const FuzzRecord& r : result.records) ++kinds[static_cast<int>(r.kind)];
  const SafetyFuzzThresholds& t = o.thresholds;
  s << "# Safety fuzz, seed " << o.seed << "\n\n"
    << result.pushes() << " pushes (" << kinds[0] << " random, " << kinds[1] << " toward joint limits, " << kinds[2]
    << " wrist folds) and " << result.faults() << " sensor faults (" << result.faults_in("rest") << " at rest, "
    << result.faults_in("motion") << " during a push, " << result.faults_in("switch") << " after a loop switch; " << kinds[4]
    << " fault-free references) on "
    << result.runs << " plant + controller constructions; " << format_fixed(result.simulated_s, 0) << " s simulated in "
    << format_fixed(result.wall_s, 1) << " s of wall time with " << o.jobs << " jobs. **" << result.controller_failures()
    << " controller failures, " << result.invalid_windows() << " invalid windows, " << result.held_command_windows()
    << " overspeeds on a held command, " << result.skipped_rows << " rows skipped.**" << (o.replay.empty() ? "" : " Replay of `" + o.replay + "` only.") << "\n\n"
    << "Violations, on the plant's true state: a joint beyond its URDF limit; |qd| above " << t.speed_factor
    << " x its velocity limit; a self-collision capsule pair below " << format_fixed(1e3 * t.collision_distance_m, 0)
    << " mm; a non-finite command; a crash or a diverged plant; a refused write (unhandled: no safe stop the next cycle); "
       "not back within "
    << t.recovery_tolerance_rad << " rad of the reference (held pose; fault-free path, or where it comes to rest after a push; dual compliance: at rest) within "
    << t.recovery_time_s << " s of the end (a fault during a push: the later of its end and the push's) plus the walk back "
       "(the largest deviation after the end, or a carried arm's distance from where the reference rests, / "
    << t.return_speed_rad_s << " rad/s, the controller's return leash), and not in a safe stop; a safe stop still moving (max abs(qd) >= " << t.rest_speed_rad_s
    << " rad/s) " << t.safe_stop_rest_time_s
    << " s after it began. Operator-possible: the push needed more than a joint's torque limit to hold the arm "
       "(|g(q) - J_p^T F|_i > tau_limit_i, controller model, true q).\n\n";
  pair_table(result, s);
  validity_section(result, s);
  category_table(result, s);
  fault_table(result, s);
  fault_kind_table(result, o, s);
  no_recovery_table(result, s);
  margins(result, s);
  held_command_list(result, o, s);
  failure_list(result, o, s);
  return s.str();
}

int run_safety_fuzz_command(const SafetyFuzzOptions& options, bool fail_on_violation, std::ostream& out) {
  out << "safety fuzz: " << (options.robot_folder.empty() ? "plant " + options.plant_config_path : "robot " + options.robot_folder)
      << ", seed " << options.seed << ", " << options.pushes
      << " random pushes" << std::endl;
  const SafetyFuzzResult r = run_safety_fuzz(options, &out);
  std::ostringstream summary;
  summary << r.pushes() << " pushes, " << r.faults() << " faults (" << r.faults_in("rest") << " at rest, " << r.faults_in("motion")
          << " in motion, " << r.faults_in("switch") << " after a loop switch), " << r.runs << " runs: " << format_fixed(r.simulated_s, 0)
          << " s simulated in " << format_fixed(r.wall_s, 1) << " s of wall time\n";
  if (!r.skipped_loops.empty()) {
    summary << "skipped: " << r.skipped_rows << " mode x loop rows (the drive does not offer " << loop_list(r.skipped_loops) << ")\n";
  }
  summary << "invalid windows: " << r.invalid_windows() << " (the loop or mode under test did not run; never a pass)\n";
  summary << "controller failures: " << r.controller_failures();
  for (int i = 0; i < kFuzzViolationCount; ++i) {
    const long n = std::count_if(r.records.begin(), r.records.end(), [i](const FuzzRecord& x) {
      return x.verdict.controller_failure() && (x.verdict.violations & (1u << i)) != 0;
    });
    if (n > 0) summary << ", " << violation_name(i) << " " << n;
  }
  summary << "\n";
  if (const long held = r.held_command_windows(); held > 0) {
    const auto w = std::max_element(r.records.begin(), r.records.end(), [](const FuzzRecord& a, const FuzzRecord& b) {
      return (a.verdict.held_command ? a.metrics.max_speed_ratio : 0.0) < (b.verdict.held_command ? b.metrics.max_speed_ratio : 0.0);
    });
    summary << "overspeed on a held command (the robot ran on a command the controller could not renew; not a controller failure, "
               "not a pass): "
            << held << ", worst " << number(w->metrics.max_speed_ratio, 3) << "x (" << w->run_id << ")\n";
  }
  if (r.faults() > 0) {
    summary << "fault windows failed:";
    for (const char* context : {"rest", "motion", "switch"}) {
      const long n = std::count_if(r.records.begin(), r.records.end(), [&](const FuzzRecord& x) {
        return x.kind == FuzzCaseKind::kFault && x.context == context && x.verdict.controller_failure();
      });
      summary << " " << context << " " << n << "/" << r.faults_in(context);
    }
    summary << "\n";
  }
  const std::vector<const FuzzRecord*> f = failures_worst_first(r);
  for (std::size_t i = 0; i < std::min<std::size_t>(f.size(), 5); ++i) {
    summary << "  " << violation_list(f[i]->verdict.violations) << ": " << what(*f[i]) << " -> " << replay_command(*f[i], options)
            << "\n";
  }
  report_experiment({summary.str(), r.files, options.output_dir, options.figure_script, "safety_fuzz.png"}, out);
  return fail_on_violation && (r.controller_failures() > 0 || r.invalid_windows() > 0) ? 1 : 0;
}

}  // namespace phri
