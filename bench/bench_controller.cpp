// One full controller cycle on the Gen3 — model terms, momentum observer, F/T wrench, compliance
// logic, QP build and solve, inverse dynamics — timed cycle by cycle over 100,000 cycles of a
// closed-loop run on MuJoCo (pushes on the elbow and the end effector every few seconds, dual
// compliance on, self-collision rows in). Reports median, p99, p99.9 and max in microseconds:
//   build/release/bench/phri_bench --benchmark_filter=ControllerCycle
#include <phri/control/compliance_controller.hpp>
#include <phri/control/momentum_observer.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/control/wrench_estimator.hpp>
#include <phri/model/algorithms.hpp>

#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <vector>

namespace {

void ControllerCycle(benchmark::State& state) {
  const std::string dir = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";
  const phri::Model model = phri::Model::from_urdf_file(dir + "gen3.urdf");
  phri::Data data(model);
  const phri::CollisionModel collision = phri::CollisionModel::from_yaml_file(dir + "collision.yaml", model);
  phri::WholeBodyQpSettings settings;
  settings.torque_limit.resize(7);
  settings.torque_limit << 95, 95, 95, 95, 26, 45, 26;
  phri::WholeBodyQp qp(model, &collision, settings);
  phri::ComplianceController compliance{phri::ComplianceSettings{}};
  phri::MomentumObserver observer(model, 50.0);
  phri::WrenchEstimator wrench(phri::WrenchEstimatorSettings{.tool_mass_kg = 0.0, .bias_samples = 1});

  char error[512];
  mjModel* m = mj_loadXML((dir + "gen3_plant.xml").c_str(), nullptr, error, sizeof(error));
  mjData* d = mj_makeData(m);
  for (int i = 0; i < 7; ++i) m->dof_armature[i] = 0.03;
  Eigen::VectorXd q(7), qd = Eigen::VectorXd::Zero(7), tau(7), tau_sensor(7);
  q << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
  for (int i = 0; i < 7; ++i) d->qpos[i] = q[i];
  mj_forward(m, d);
  phri::compute_all_terms(model, data, q, qd);
  qp.posture().set_target(q);
  compliance.initialise(phri::ComplianceMode::kDual, qp, data);
  tau = tau_sensor = data.gravity_torque;
  const int ee = model.frame_id("end_effector_link");
  const int forearm = mj_name2id(m, mjOBJ_BODY, "forearm_link");
  const int bracelet = mj_name2id(m, mjOBJ_BODY, "bracelet_link");

  constexpr int kCycles = 100000;
  std::vector<double> micros(kCycles);
  for (auto _ : state) {
    for (int k = 0; k < kCycles; ++k) {
      const double t = k * 1e-3;
      const double phase = std::fmod(t, 6.0);
      const bool push_elbow = phase > 1.0 && phase < 2.0;
      const bool push_ee = phase > 3.0 && phase < 4.0;
      for (int i = 0; i < 7; ++i) {
        q[i] = d->qpos[i];
        qd[i] = d->qvel[i];
      }
      phri::Vector6d ft = phri::Vector6d::Zero();
      if (push_ee) ft[1] = 12.0;
      const auto start = std::chrono::steady_clock::now();
      // ---- the controller cycle
      phri::compute_all_terms(model, data, q, qd);
      phri::coriolis_transpose_times_velocity(model, data);
      observer.update(data, qd, tau_sensor, 1e-3);
      const Eigen::Isometry3d& flange = data.frame_placements[static_cast<std::size_t>(ee)];
      wrench.update(ft, flange, flange.translation());
      compliance.update(wrench.norm(), qp, data);
      qp.update(model, data, q, qd, observer.external_torque(), 1e-3);
      tau = qp.desired_torque();
      // ----
      micros[static_cast<std::size_t>(k)] =
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
      for (int s = 0; s < 4; ++s) {
        for (int i = 0; i < 7; ++i) d->qfrc_applied[i] = tau[i] + 0.03 * qp.desired_acceleration()[i];
        mjtNum force[3] = {0, 0, 0}, torque[3] = {0, 0, 0}, point[3];
        if (push_elbow || push_ee) {
          const int body = push_elbow ? forearm : bracelet;
          force[1] = push_elbow ? 30.0 : 12.0;
          for (int c = 0; c < 3; ++c) point[c] = d->xpos[3 * body + c];
          mj_applyFT(m, d, force, torque, point, body, d->qfrc_applied);
        }
        mj_step(m, d);
      }
      for (int i = 0; i < 7; ++i) tau_sensor[i] = tau[i] + 0.03 * (qp.desired_acceleration()[i] - d->qacc[i]);
    }
  }
  std::vector<double> sorted = micros;
  std::sort(sorted.begin(), sorted.end());
  auto pct = [&](double p) { return sorted[static_cast<std::size_t>(p * (kCycles - 1))]; };
  state.counters["median_us"] = pct(0.5);
  state.counters["p99_us"] = pct(0.99);
  state.counters["p99.9_us"] = pct(0.999);
  state.counters["max_us"] = sorted.back();
  state.counters["touches"] = compliance.touch_count();
  mj_deleteData(d);
  mj_deleteModel(m);
}
BENCHMARK(ControllerCycle)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
