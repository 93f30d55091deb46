// ctest-labels: physics
// ISO 9283 pose test (experiments/iso9283.hpp): the cube's five poses and the AP/RP formulas
// against closed forms written out here, then a short run on the simulated plant that checks the
// loop it names ran (a loop the drive does not offer is reported invalid, not measured).
#include <phri/experiments/iso9283.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

TEST(Iso9283, CubePosesAreTheCentreAndFourPointsOnTheDiagonalPlaneTenPercentFromItsCorners) {
  const Eigen::Vector3d c(0.4, -0.1, 0.5);
  const double side = 0.2;
  const std::vector<Eigen::Vector3d> p = phri::iso9283_cube_poses(c, side);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_LT((p[0] - c).norm(), 1e-15);
  const double half_diagonal = 0.5 * side * std::sqrt(3.0);
  for (int i = 1; i < 5; ++i) {
    // 10 % of the diagonal (length 2 half_diagonal) from the corner: 0.8 half_diagonal from the centre.
    EXPECT_NEAR((p[static_cast<std::size_t>(i)] - c).norm(), 0.8 * half_diagonal, 1e-12);
    // In the plane through C1 C2 C7 C8 (x = y relative to the centre).
    EXPECT_NEAR((p[static_cast<std::size_t>(i)] - c).dot(Eigen::Vector3d(1, -1, 0)), 0.0, 1e-12);
  }
  // P2 and P4, P3 and P5 are opposite ends of the plane's two diagonals.
  EXPECT_LT((p[1] + p[3] - 2 * c).norm(), 1e-12);
  EXPECT_LT((p[2] + p[4] - 2 * c).norm(), 1e-12);
}

TEST(Iso9283, AccuracyAndRepeatabilityFollowTheStandardsFormulas) {
  // Attained - commanded: a bias b plus a spread of +-d along x and 2d along y on alternate arrivals.
  const Eigen::Vector3d b(0.3e-3, -0.4e-3, 0.0);  // |b| = 0.5 mm
  const double d = 0.1e-3;
  std::vector<phri::Iso9283Arrival> arrivals;
  const Eigen::Vector3d offsets[4] = {{d, 0, 0}, {-d, 0, 0}, {0, 2 * d, 0}, {0, -2 * d, 0}};
  for (const Eigen::Vector3d& o : offsets) {
    phri::Iso9283Arrival a;
    a.position_error_m = b + o;
    a.orientation_error_rad = Eigen::Vector3d(0.01, 0.0, 0.0) + o / d * 1e-3;
    a.stabilisation_s = {0.1, 0.05};
    arrivals.push_back(a);
  }
  const phri::Iso9283Pose f = phri::iso9283_pose_figures(arrivals);
  EXPECT_NEAR(f.ap_mm, 0.5, 1e-12);
  // l_j = 0.1, 0.1, 0.2, 0.2 mm: l_mean 0.15, S_l = sqrt(4 x 0.05^2 / 3) mm.
  EXPECT_NEAR(f.rp_mm, 0.15 + 3.0 * std::sqrt(4.0 * 0.05 * 0.05 / 3.0), 1e-12);
  // The orientation: a = 0.01 + (1, -1, 0, 0) 1e-3 rad, b = (0, 0, 2, -2) 1e-3 rad.
  EXPECT_NEAR(f.ap_deg[0], 0.01 * 180.0 / M_PI, 1e-12);
  EXPECT_NEAR(f.ap_deg[1], 0.0, 1e-12);
  EXPECT_NEAR(f.rp_deg[0], 3.0 * std::sqrt(2e-6 / 3.0) * 180.0 / M_PI, 1e-12);
  EXPECT_NEAR(f.rp_deg[1], 3.0 * std::sqrt(8e-6 / 3.0) * 180.0 / M_PI, 1e-12);
  EXPECT_EQ(f.arrivals, 4);
  EXPECT_DOUBLE_EQ(f.stabilisation_median_s[0], 0.1);
  EXPECT_DOUBLE_EQ(f.stabilisation_max_s[1], 0.05);
}

phri::Iso9283Options short_run(std::vector<phri::LowLevelMode> loops) {
  phri::Iso9283Options o;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path}) {
    *path = kRoot + "/" + *path;
  }
  o.output_dir.clear();
  o.cycles = 2;
  o.dwell_s = 0.6;
  o.loops = std::move(loops);
  return o;
}

TEST(Iso9283, TwoCyclesOnThePlantRunInTheLoopsTheyNameAndThePositionLoopReachesThePoses) {
  const phri::Iso9283Result r = phri::run_iso9283(short_run({phri::LowLevelMode::kPosition, phri::LowLevelMode::kCurrent}));
  ASSERT_EQ(r.loops.size(), 2u);
  for (const phri::Iso9283Loop& l : r.loops) {
    EXPECT_TRUE(l.valid) << l.invalid_reason;
    ASSERT_EQ(l.arrivals.size(), 10u);
    for (const phri::Iso9283Pose& p : l.poses) EXPECT_EQ(p.arrivals, 2);
  }
  double worst_ap = 0.0;
  for (const phri::Iso9283Pose& p : r.loops[0].poses) worst_ap = std::max(worst_ap, p.ap_mm);
  std::printf("ISO 9283, 2 cycles: position loop worst AP %.3f mm\n", worst_ap);
  EXPECT_LT(worst_ap, 0.5);
  // Every link's power-and-force-limiting figures on the plant's truth, each its speed over its v_max.
  for (const phri::Iso9283Loop& l : r.loops) {
    ASSERT_EQ(l.contact.size(), 8u);  // the Gen3's links with a capsule, but the base's
    double fastest = 0.0;
    for (const phri::ContactLinkSummary& c : l.contact) {
      if (c.max_ratio > 0.0) {
        EXPECT_NEAR(c.max_ratio, c.speed_at_max_m_s / c.permissible_speed_at_max_m_s, 1e-12);
      }
      fastest = std::max(fastest, c.max_speed_m_s);
    }
    EXPECT_GT(fastest, 0.2) << "moves at 250 mm/s peak";
    EXPECT_LT(fastest, 0.4);
  }
  EXPECT_NE(phri::iso9283_table(r).find("| position | spherical_wrist"), std::string::npos) << phri::iso9283_table(r);
  // The commanded poses span the cube: a run that did not move would fail the accuracy above.
  EXPECT_NEAR((r.commanded[1] - r.commanded[3]).norm(), 0.8 * 0.2 * std::sqrt(3.0), 1e-9);
}

TEST(Iso9283, ALoopTheDriveDoesNotOfferIsReportedInvalidNotMeasured) {
  const phri::Iso9283Result r = phri::run_iso9283(short_run({phri::LowLevelMode::kTorque}));
  ASSERT_EQ(r.loops.size(), 1u);
  EXPECT_FALSE(r.loops[0].valid);
  // The plant refuses every torque write (Kinova has no plain torque mode).
  EXPECT_NE(r.loops[0].invalid_reason.find("refused writes"), std::string::npos) << r.loops[0].invalid_reason;
  EXPECT_NE(phri::iso9283_table(r).find("NO: "), std::string::npos);
}

}  // namespace
