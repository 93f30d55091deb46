// ctest-labels: physics
// The momentum observer against MuJoCo: the Gen3 moves under known joint torques while MuJoCo
// applies an external force to the forearm; the observer, fed only q, qd and the joint torques,
// must find J^T F with its first-order response.
#include <phri/control/momentum_observer.hpp>
#include <phri/model/algorithms.hpp>

#include "allocation_counter.hpp"
#include "mujoco_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

TEST(MomentumObserver, FindsAnExternalForceOnTheForearmWhileTheArmMoves) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  auto mj = phri::test::MujocoReference::from_file(kGen3 + "gen3_plant.xml");
  mj.bind(model);
  const mjModel* m = mj.model();
  mjData* d = mj.data();
  const int substeps = 4;  // 4 kHz physics under a 1 kHz observer
  const double dt = substeps * m->opt.timestep;
  ASSERT_NEAR(dt, 1e-3, 1e-12);

  Eigen::VectorXd q(7);
  q << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
  mj.set_state(q, Eigen::VectorXd::Zero(7), Eigen::VectorXd::Zero(7));
  const Eigen::VectorXd q_start = q;
  const int forearm = mj.body_id("forearm_link");
  const Eigen::Vector3d force(0.0, 20.0, -10.0);

  const double gain = 50.0;
  phri::MomentumObserver observer(model, gain);
  Eigen::VectorXd qd(7), tau(7), expected(7);
  Eigen::MatrixXd jacobian_com(6, 7);
  double worst_late_error = 0.0, max_expected = 0.0;
  for (int k = 0; k <= 1500; ++k) {
    const double t = k * dt;
    for (int i = 0; i < 7; ++i) {
      q[i] = d->qpos[i];
      qd[i] = d->qvel[i];
    }
    phri::compute_all_terms(model, data, q, qd);
    phri::coriolis_transpose_times_velocity(model, data);
    // Joint torques: gravity compensation, a loose PD around the start posture (so that the arm
    // swings but stays away from its joint limits, whose constraint forces MuJoCo would add) and a
    // sinusoidal drive of every joint. Wrist gains are small enough to stay stable when held over
    // a control period on those light joints.
    for (int i = 0; i < 7; ++i) {
      const bool large = i < 4;
      tau[i] = data.gravity_torque[i] + (large ? 40.0 : 1.0) * (q_start[i] - q[i]) - (large ? 4.0 : 0.02) * qd[i] +
               (large ? 2.0 : 0.05) * std::sin(3.0 * t + i);
    }
    observer.update(data, qd, tau, dt);
    // The force acts from t = 0.2 s on, at the forearm's centre of mass.
    const bool pushed = t >= 0.2;
    if (pushed) {
      const Eigen::Vector3d com(d->xipos[3 * forearm], d->xipos[3 * forearm + 1], d->xipos[3 * forearm + 2]);
      expected = mj.point_jacobian(forearm, com).topRows<3>().transpose() * force;
      max_expected = std::max(max_expected, expected.cwiseAbs().maxCoeff());
      // After 5 time constants the first-order response has settled (e^-5 < 1 %).
      if (t > 0.2 + 5.0 / gain) {
        worst_late_error = std::max(worst_late_error, (observer.external_torque() - expected).cwiseAbs().maxCoeff());
      }
    } else {
      EXPECT_LT(observer.external_torque().cwiseAbs().maxCoeff(), 0.05) << "t = " << t;  // no push: ~0
    }
    for (int i = 0; i < 7; ++i) d->qfrc_applied[i] = tau[i];
    for (int c = 0; c < 3; ++c) d->xfrc_applied[6 * forearm + c] = pushed ? force[c] : 0.0;
    for (int s = 0; s < substeps; ++s) mj_step(m, d);
  }
  std::printf("observer: worst |r - J^T F| after settling = %.4f N.m (max |J^T F| %.2f N.m)\n", worst_late_error,
              max_expected);
  EXPECT_GT(max_expected, 5.0);
  // The arm moves during the push, so J^T F changes: the lag of the first-order filter
  // (1/K_O = 20 ms) and the 1 ms discretisation leave a small error.
  EXPECT_LT(worst_late_error, 0.03 * max_expected);
}

TEST(MomentumObserver, StepResponseIsFirstOrderWithTheGain) {
  // A static arm with a constant external torque: r follows 1 - e^{-K t} (to first order in K dt).
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3), qd = Eigen::VectorXd::Zero(7);
  phri::compute_all_terms(model, data, q, qd);
  phri::coriolis_transpose_times_velocity(model, data);
  const double gain = 10.0, dt = 1e-3;
  phri::MomentumObserver observer(model, gain);
  observer.reset(data, qd);
  Eigen::VectorXd external = Eigen::VectorXd::LinSpaced(7, -2.0, 3.0);
  // Static equilibrium: tau_s = g - tau_ext (the sensor carries what the push does not).
  const Eigen::VectorXd tau_sensor = data.gravity_torque - external;
  phri::test::AllocationCounter count;
  for (int k = 1; k <= 100; ++k) observer.update(data, qd, tau_sensor, dt);
  EXPECT_EQ(count.allocations(), 0u);
  // After 0.1 s = one time constant: 1 - e^-1 of the step (the discrete recursion gives
  // 1 - (1 - K dt)^k, within 0.2 % of it here).
  const double fraction = observer.external_torque().dot(external) / external.squaredNorm();
  EXPECT_NEAR(fraction, 1.0 - std::exp(-1.0), 0.01);
  for (int k = 0; k < 1000; ++k) observer.update(data, qd, tau_sensor, dt);
  EXPECT_LT((observer.external_torque() - external).norm(), 1e-4);
}

// The release path (set_release_path): while the kick -M^-1 r would drive a joint faster than
// its release speed along its motion, a push that ends is followed by the fast observer (pole
// 1 - K_r T) within the threshold; otherwise, and at every onset, the K_O low-pass holds bit for
// bit. Constant momentum (q and qd held): tau_s = g - C^T qd - tau_ext, and each observer follows
// r[k] = (1 - K T) r[k-1] + K T tau_ext[k], so the values after the release are closed forms.
TEST(MomentumObserver, ReleasePathDropsAPushThatEndsOnlyWhenItsKickDrivesAFastJoint) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3);
  const double gain = 50.0, release_gain = 500.0, threshold = 5.0, dt = 1e-3;
  struct Case {
    const char* what;
    double speed;   // joint 3's [rad/s]; the others rest
    double push;    // on joint 3 [N.m]; the kick -M^-1 r on joint 3 has the sign of -push
    bool released;
  };
  for (const Case c : {Case{"pushed against its motion", 1.5, -20.0, true}, Case{"pushed along its motion", 1.5, 20.0, false},
                       Case{"slower than the release speed", 0.5, -20.0, false}, Case{"at rest", 0.0, -20.0, false}}) {
    SCOPED_TRACE(c.what);
    Eigen::VectorXd qd = Eigen::VectorXd::Zero(7);
    qd[2] = c.speed;
    phri::compute_all_terms(model, data, q, qd);
    phri::coriolis_transpose_times_velocity(model, data);
    phri::MomentumObserver plain(model, gain), released(model, gain);
    released.set_release_path(release_gain, threshold, Eigen::VectorXd::Constant(7, 1.0));
    plain.reset(data, qd);
    released.reset(data, qd);
    Eigen::VectorXd external = Eigen::VectorXd::Zero(7);
    external[2] = c.push;
    const Eigen::VectorXd balance = data.gravity_torque - data.coriolis_transpose_qd;
    const Eigen::VectorXd pushed = balance - external;
    phri::test::AllocationCounter count;
    for (int k = 0; k < 400; ++k) {
      plain.update(data, qd, pushed, dt);
      released.update(data, qd, pushed, dt);
    }
    EXPECT_EQ(count.allocations(), 0u);
    EXPECT_EQ((plain.external_torque() - released.external_torque()).cwiseAbs().maxCoeff(), 0.0) << "the onset is untouched";
    for (int k = 0; k < 5; ++k) {  // the push has ended: five periods later
      plain.update(data, qd, balance, dt);
      released.update(data, qd, balance, dt);
    }
    const double r = released.external_torque()[2], slow = plain.external_torque()[2];
    std::printf("%s: joint 3 five periods after the release %.4f N.m (K_O alone %.4f)\n", c.what, r, slow);
    EXPECT_NEAR(slow, c.push * std::pow(1.0 - gain * dt, 5), 1e-6);
    if (c.released) {
      EXPECT_NEAR(r, c.push * std::pow(1.0 - release_gain * dt, 5) + std::copysign(threshold, c.push), 1e-6);
    } else {
      EXPECT_EQ(r, slow);
    }
    for (int i : {0, 1, 3, 4, 5, 6}) EXPECT_NEAR(released.external_torque()[i], plain.external_torque()[i], 1e-9);
  }
}

// After missed periods (dt = 10 ms here) the release path's step would be gain x dt = 5 times the
// error, an overshoot of 5x the push: it takes at most a deadbeat step (r_fast = tau_ext at once),
// and its state stays consistent with its gain, so the next 1 ms steps hold tau_ext. The K_O
// observer (gain x dt = 0.5) keeps its own recursion, r = 0.5 tau_ext. Constant momentum:
// tau_s = g - C^T qd - tau_ext.
TEST(MomentumObserver, TheFastEstimateTakesAtMostADeadbeatStepAfterAGap) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3);
  Eigen::VectorXd qd = Eigen::VectorXd::Zero(7);
  qd[2] = 0.4;
  phri::compute_all_terms(model, data, q, qd);
  phri::coriolis_transpose_times_velocity(model, data);
  phri::MomentumObserver observer(model, 50.0);
  observer.set_release_path(500.0, 5.0, Eigen::VectorXd::Constant(7, 1.0));
  observer.reset(data, qd);
  const Eigen::VectorXd external = Eigen::VectorXd::LinSpaced(7, -4.0, 3.0);
  const Eigen::VectorXd pushed = data.gravity_torque - data.coriolis_transpose_qd - external;
  observer.update(data, qd, pushed, 0.010);
  EXPECT_LT((observer.fast_external_torque() - external).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((observer.external_torque() - 0.5 * external).cwiseAbs().maxCoeff(), 1e-9);
  for (int k = 0; k < 3; ++k) observer.update(data, qd, pushed, 0.001);
  EXPECT_LT((observer.fast_external_torque() - external).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((observer.external_torque() - (1.0 - 0.5 * std::pow(0.95, 3)) * external).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
