// ctest-labels: unit
// Observers of the run (RunOptions::observers): every observer gets the cycle's snapshots through
// its own lock-free ring; a slow observer loses snapshots (counted as dropped) and never holds the
// cycle; the loop side allocates nothing per cycle with several observers. Driven through
// phri::FakeRobot with the Gen3 controller and the FSM's start-up, in lockstep.
#include <phri/app/fsm.hpp>
#include <phri/app/run_session.hpp>
#include <phri/app/snapshot_channel.hpp>
#include <phri/control/controller.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/fake_robot.hpp>

#include "allocation_counter.hpp"
#include "gen3_settings.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <sstream>
#include <thread>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

phri::FakeRobotSettings fake_gen3() {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kGen3 + "actuators.yaml");
  phri::FakeRobotSettings s;
  s.dof = 7;
  s.period_s = 1e-3;
  s.initial_q_rad.resize(7);
  s.initial_q_rad << 0.0, 0.26179939, 3.14159265, -2.26892803, 0.0, 0.95993109, 1.57079633;
  s.torque_per_amp_Nm_per_A.resize(7);
  for (int i = 0; i < 7; ++i) s.torque_per_amp_Nm_per_A[i] = table[i].torque_per_amp();
  return s;
}

struct ObservedRun {
  ObservedRun() : controller(phri::test::gen3_controller_settings()), fsm(phri::FsmSettings{}, controller) {}
  phri::RunSummary run(double duration_s, std::vector<phri::SnapshotChannel*> observers) {
    phri::RunOptions options;
    options.duration_s = duration_s;
    options.status_line = false;
    options.observers = std::move(observers);
    return phri::run_session(robot, controller, fsm, nullptr, nullptr, options, out);
  }
  phri::FakeRobot robot{fake_gen3()};
  phri::Controller controller;
  phri::Fsm fsm;
  std::ostringstream out;
};

TEST(RunObservers, TwoObserversBothReceiveTheCyclesSnapshots) {
  phri::SnapshotChannel every_cycle({.decimation = 1, .capacity = 1024});
  phri::SnapshotChannel every_tenth({.decimation = 10, .capacity = 1024});
  ObservedRun run;
  const phri::RunSummary summary = run.run(0.5, {&every_cycle, &every_tenth});
  ASSERT_EQ(summary.cycles, 500u);
  EXPECT_EQ(every_cycle.published(), 500u);
  EXPECT_EQ(every_tenth.published(), 50u);
  EXPECT_EQ(every_cycle.dropped() + every_tenth.dropped(), 0u);
  // In cycle order, each the cycle as logged.
  phri::LiveSnapshot s;
  std::int64_t previous = 0;
  int n = 0;
  while (every_cycle.next_snapshot(s)) {
    if (n > 0) {
      EXPECT_EQ(s.row.cycle, previous + 1);
    }
    previous = s.row.cycle;
    EXPECT_EQ(s.dof, 7);
    ++n;
  }
  EXPECT_EQ(n, 500);
  n = 0;
  while (every_tenth.next_snapshot(s)) ++n;
  EXPECT_EQ(n, 50);
}

// An observer whose thread takes 20 ms per snapshot would need 10 s for the run's 500 if the loop
// waited for it; the loop publishes into its ring and moves on: the run ends long before, the slow
// observer's ring full and the rest counted as dropped, and the fast observer misses nothing.
TEST(RunObservers, ASlowObserverDoesNotSlowTheCycle) {
  phri::SnapshotChannel fast({.decimation = 1, .capacity = 1024});
  phri::SnapshotChannel slow({.decimation = 1, .capacity = 8});
  std::atomic<bool> done{false};
  std::atomic<int> slow_read{0};
  std::thread slow_reader([&] {
    phri::LiveSnapshot s;
    while (!done.load()) {
      if (slow.next_snapshot(s)) ++slow_read;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  ObservedRun run;
  const auto start = std::chrono::steady_clock::now();
  const phri::RunSummary summary = run.run(0.5, {&slow, &fast});
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  done.store(true);
  slow_reader.join();
  ASSERT_EQ(summary.cycles, 500u);
  EXPECT_LT(wall_s, 5.0) << "the loop waited for the slow observer";
  EXPECT_EQ(fast.published(), 500u);
  EXPECT_EQ(fast.dropped(), 0u);
  EXPECT_EQ(slow.published() + slow.dropped(), 500u);
  EXPECT_GT(slow.dropped(), 400u);
  EXPECT_LE(static_cast<std::uint64_t>(slow_read.load()), slow.published());
}

// The loop side of two observers allocates nothing per cycle: a run twice as long allocates the
// same (what allocates is sized before the loop).
TEST(RunObservers, TheLoopSideAllocatesNothingPerCycle) {
  if (!phri::test::counts_malloc()) GTEST_SKIP() << "allocations are not counted under the sanitizer";
  auto allocations = [](double duration_s) {
    phri::SnapshotChannel a({.decimation = 1, .capacity = 16});
    phri::SnapshotChannel b({.decimation = 3, .capacity = 4096});
    ObservedRun run;
    const phri::test::AllocationCounter count;
    run.run(duration_s, {&a, &b});
    return count.allocations();
  };
  EXPECT_EQ(allocations(0.2), allocations(0.4));
}

}  // namespace
