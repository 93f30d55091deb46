// phri_replay_cycle: the controller cycle replayed open loop on recorded states, to compare what two
// builds of the controller compute on the same inputs. A closed-loop log cannot do that: the
// plant's stick-slip and contacts carry a rounding change of 1e-16 in one cycle to whole newtons
// later, so two builds that agree to rounding still write different logs.
//
//   phri_replay_cycle record STATES [--cycles N]   the controller benchmark's pushed Gen3 closed loop
//                                                  (bench/pushed_gen3.hpp), each cycle's RobotState
//   phri_replay_cycle replay STATES OUT            a fresh controller stepped on those states; per
//                                                  cycle its mode, qdd_d, tau_d and command; prints
//                                                  the step's median and p99 wall time (same inputs
//                                                  for both builds, unlike a closed-loop benchmark)
//   phri_replay_cycle compare OUT_A OUT_B          the largest difference per quantity and where
//
// Build the replay against two versions of the library (same STATES file) and compare their OUTs.
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/core/statistics.hpp>
#include <phri/sim/sim_robot.hpp>

#include "pushed_gen3.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr char kStatesMagic[8] = {'P', 'H', 'R', 'I', 'S', 'T', 'A', '1'};
constexpr char kOutputMagic[8] = {'P', 'H', 'R', 'I', 'O', 'U', 'T', '1'};

phri::Controller make_controller() {
  phri::ControllerSettings settings;
  phri::RobotBundle::from_folder(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3").apply_to(settings);
  settings.initial_compliance = phri::ComplianceMode::kDual;  // as ControllerCycle (bench_controller.cpp)
  return phri::Controller(settings);
}

template <typename T>
void put(std::ofstream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}
template <typename T>
T get(std::ifstream& in) {
  T value{};
  in.read(reinterpret_cast<char*>(&value), sizeof(T));
  if (!in) throw std::runtime_error("file ends in the middle of a record");
  return value;
}
void put_vector(std::ofstream& out, const Eigen::VectorXd& v) { out.write(reinterpret_cast<const char*>(v.data()), v.size() * 8); }
void get_vector(std::ifstream& in, Eigen::VectorXd& v) {
  in.read(reinterpret_cast<char*>(v.data()), v.size() * 8);
  if (!in) throw std::runtime_error("file ends in the middle of a record");
}
void put_signal(std::ofstream& out, const phri::SignalStatus& s) {
  put(out, static_cast<std::uint8_t>(s.valid));
  put(out, s.sequence);
  put(out, s.stamp_s);
}
phri::SignalStatus get_signal(std::ifstream& in) {
  phri::SignalStatus s;
  s.valid = get<std::uint8_t>(in) != 0;
  s.sequence = get<std::uint32_t>(in);
  s.stamp_s = get<double>(in);
  return s;
}

void write_state(std::ofstream& out, const phri::RobotState& s) {
  put(out, s.time_s);
  put(out, s.cycle);
  put(out, static_cast<std::int32_t>(s.mode));
  put_vector(out, s.q_rad);
  put_vector(out, s.qd_rad_s);
  put_vector(out, s.tau_sensor_Nm);
  put_vector(out, s.current_A);
  out.write(reinterpret_cast<const char*>(s.wrench_sensor.data()), 6 * 8);
  for (const phri::SignalStatus* signal : {&s.joints, &s.torque, &s.current, &s.wrench}) put_signal(out, *signal);
  put(out, static_cast<std::uint8_t>(s.fault));
  put(out, static_cast<std::uint8_t>(s.stop_requested));
  put(out, static_cast<std::int32_t>(s.last_write_status));
  put(out, s.rejected_writes);
}

void read_state(std::ifstream& in, phri::RobotState& s) {
  s.time_s = get<double>(in);
  s.cycle = get<std::uint64_t>(in);
  s.mode = static_cast<phri::LowLevelMode>(get<std::int32_t>(in));
  get_vector(in, s.q_rad);
  get_vector(in, s.qd_rad_s);
  get_vector(in, s.tau_sensor_Nm);
  get_vector(in, s.current_A);
  in.read(reinterpret_cast<char*>(s.wrench_sensor.data()), 6 * 8);
  s.joints = get_signal(in);
  s.torque = get_signal(in);
  s.current = get_signal(in);
  s.wrench = get_signal(in);
  s.fault = get<std::uint8_t>(in) != 0;
  s.stop_requested = get<std::uint8_t>(in) != 0;
  s.last_write_status = static_cast<phri::WriteStatus>(get<std::int32_t>(in));
  s.rejected_writes = get<std::uint64_t>(in);
}

void read_header(std::ifstream& in, const char (&magic)[8], const std::string& path, std::int32_t& dof, std::int64_t& count) {
  char found[8];
  in.read(found, 8);
  if (!in || std::memcmp(found, magic, 8) != 0) throw std::runtime_error(path + ": not a file of this kind");
  dof = get<std::int32_t>(in);
  count = get<std::int64_t>(in);
}

int record(const std::string& path, long cycles) {
  const phri::SimRobotConfig plant = pushed_gen3_plant(static_cast<double>(cycles) * 1e-3);
  phri::SimRobot robot(plant);
  phri::Controller controller = make_controller();
  phri::RobotCommand command(robot.dof());
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path);
  out.write(kStatesMagic, 8);
  put(out, static_cast<std::int32_t>(robot.dof()));
  put(out, static_cast<std::int64_t>(cycles));
  for (long k = 0; k < cycles; ++k) {
    const phri::RobotState& s = robot.read();
    write_state(out, s);
    controller.step(s, command);
    robot.write(command);
  }
  std::printf("%s: %ld states of the pushed Gen3 closed loop\n", path.c_str(), cycles);
  return 0;
}

int replay(const std::string& states_path, const std::string& out_path) {
  std::ifstream in(states_path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + states_path);
  std::int32_t dof = 0;
  std::int64_t count = 0;
  read_header(in, kStatesMagic, states_path, dof, count);
  phri::Controller controller = make_controller();
  if (controller.model().nv() != dof) throw std::runtime_error(states_path + ": recorded for another arm");
  phri::RobotState state(dof);
  phri::RobotCommand command(dof);
  std::ofstream out(out_path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + out_path);
  out.write(kOutputMagic, 8);
  put(out, dof);
  put(out, count);
  std::vector<double> micros(static_cast<std::size_t>(count));
  for (std::int64_t k = 0; k < count; ++k) {
    read_state(in, state);
    const auto start = std::chrono::steady_clock::now();
    controller.step(state, command);
    micros[static_cast<std::size_t>(k)] =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    put(out, static_cast<std::int32_t>(command.mode));
    put_vector(out, controller.qp().desired_acceleration());
    put_vector(out, controller.qp().desired_torque());
    put_vector(out, command.q_rad);
    put_vector(out, command.tau_Nm);
    put_vector(out, command.current_A);
  }
  std::printf("%s: %lld cycles replayed; step median %.3f us, p99 %.3f us\n", out_path.c_str(),
              static_cast<long long>(count), phri::percentile(micros, 0.5), phri::percentile(micros, 0.99));
  return 0;
}

int compare(const std::string& a_path, const std::string& b_path) {
  std::ifstream a(a_path, std::ios::binary), b(b_path, std::ios::binary);
  if (!a || !b) throw std::runtime_error("cannot read " + (a ? b_path : a_path));
  std::int32_t dof_a = 0, dof_b = 0;
  std::int64_t count_a = 0, count_b = 0;
  read_header(a, kOutputMagic, a_path, dof_a, count_a);
  read_header(b, kOutputMagic, b_path, dof_b, count_b);
  if (dof_a != dof_b || count_a != count_b) throw std::runtime_error("the two replays are of different runs");
  const char* names[] = {"qdd_d [rad/s^2]", "tau_d [N.m]", "command q [rad]", "command tau [N.m]", "command current [A]"};
  constexpr int kQuantities = 5;
  double largest[kQuantities] = {};
  std::int64_t where[kQuantities] = {}, above[kQuantities] = {};
  std::int64_t mode_differs = 0, identical = 0;
  Eigen::VectorXd x(dof_a), y(dof_a);
  for (std::int64_t k = 0; k < count_a; ++k) {
    mode_differs += get<std::int32_t>(a) != get<std::int32_t>(b);
    bool same = true;
    for (int i = 0; i < kQuantities; ++i) {
      get_vector(a, x);
      get_vector(b, y);
      const double d = (x - y).cwiseAbs().maxCoeff();
      same = same && d == 0.0;
      above[i] += d > 1e-9;
      if (d > largest[i] || std::isnan(d)) {
        largest[i] = d;
        where[i] = k;
      }
    }
    identical += same;
  }
  std::printf("%lld cycles: %lld bit for bit, the mode differs on %lld\n", static_cast<long long>(count_a),
              static_cast<long long>(identical), static_cast<long long>(mode_differs));
  std::printf("%-22s %12s %10s %14s\n", "quantity", "largest", "at cycle", "cycles > 1e-9");
  for (int i = 0; i < kQuantities; ++i) {
    std::printf("%-22s %12.3e %10lld %14lld\n", names[i], largest[i], static_cast<long long>(where[i]),
                static_cast<long long>(above[i]));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string verb = argc > 1 ? argv[1] : "";
    if (verb == "record" && (argc == 3 || (argc == 5 && std::strcmp(argv[3], "--cycles") == 0))) {
      const long cycles = argc == 5 ? std::strtol(argv[4], nullptr, 10) : 100000;
      if (cycles <= 0) throw std::runtime_error("--cycles must be a positive count");
      return record(argv[2], cycles);
    }
    if (verb == "replay" && argc == 4) return replay(argv[2], argv[3]);
    if (verb == "compare" && argc == 4) return compare(argv[2], argv[3]);
    std::fprintf(stderr,
                 "usage: phri_replay_cycle record STATES [--cycles N] | replay STATES OUT | compare OUT_A OUT_B\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "phri_replay_cycle: %s\n", e.what());
    return 1;
  }
}
