// ctest-labels: unit
// Capsules fitted from a URDF (model/capsule_fit.hpp): on the Gen3 (no collision geometry in its
// URDF: link frames), the fitted axes are the hand-written collision.yaml's, which were copied from
// the URDF's joint origins; on boxes, cylinders and spheres, the capsule encloses every point of
// the geometry (random samples) and is tight on a cylinder; no pair is adjacent or in contact at
// the home posture.
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/capsule_fit.hpp>
#include <phri/model/collision_model.hpp>

#include "generated_arm.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

const phri::Capsule* capsule_of(const phri::CollisionModel& c, const std::string& link) {
  for (const phri::Capsule& capsule : c.capsules()) {
    if (capsule.link == link) return &capsule;
  }
  return nullptr;
}

Eigen::VectorXd gen3_home() {
  Eigen::VectorXd q(7);
  q << 0.0, 0.26179939, 3.14159265, -2.26892803, 0.0, 0.95993109, 1.57079633;
  return q;
}

TEST(CapsuleFit, Gen3LinkFrameAxesAreTheHandWrittenOnes) {
  const std::string urdf = read_file(kGen3 + "gen3.urdf");
  const phri::Model model = phri::Model::from_urdf_string(urdf);
  const phri::CapsuleFit fit = phri::fit_capsules(urdf, model, gen3_home(), {.link_frame_radius_m = 0.04, .clearance_m = 0.0});
  const phri::CollisionModel fitted = phri::CollisionModel::from_yaml_string(fit.yaml, model, "fitted");
  const phri::CollisionModel hand = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model);
  EXPECT_EQ(fit.capsules, 8);  // base and the seven moving links
  for (const char* link : {"shoulder_link", "half_arm_1_link", "half_arm_2_link", "forearm_link", "spherical_wrist_1_link",
                           "spherical_wrist_2_link", "bracelet_link"}) {
    SCOPED_TRACE(link);
    const phri::Capsule* a = capsule_of(fitted, link);
    const phri::Capsule* b = capsule_of(hand, link);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->body, b->body);
    EXPECT_LT((a->p0 - b->p0).norm(), 1e-9);
    EXPECT_LT((a->p1 - b->p1).norm(), 1e-9);
  }
}

// Every pair: not on one body, not adjacent, clear at the home posture by the clearance.
void expect_pairs_valid(const phri::CapsuleFit& fit, const phri::Model& model, const Eigen::VectorXd& home, double clearance) {
  const phri::CollisionModel c = phri::CollisionModel::from_yaml_string(fit.yaml, model, "fitted");
  EXPECT_EQ(c.num_pairs(), fit.pairs);
  phri::Data data(model);
  phri::forward_kinematics(model, data, home);
  phri::CollisionData d(model, c);
  phri::compute_collision_distances(model, data, c, d, false);
  for (int k = 0; k < c.num_pairs(); ++k) {
    const auto& pair = c.pairs()[static_cast<std::size_t>(k)];
    EXPECT_GT(std::abs(c.capsules()[static_cast<std::size_t>(pair.first)].body - c.capsules()[static_cast<std::size_t>(pair.second)].body), 1);
    EXPECT_GE(d.distance[k], clearance);
  }
}

TEST(CapsuleFit, PairsAreNeitherAdjacentNorInContactAtHome) {
  const std::string urdf = read_file(kGen3 + "gen3.urdf");
  const phri::Model model = phri::Model::from_urdf_string(urdf);
  for (double clearance : {0.0, 0.05}) {
    const phri::CapsuleFit fit = phri::fit_capsules(urdf, model, gen3_home(), {.link_frame_radius_m = 0.045, .clearance_m = clearance});
    expect_pairs_valid(fit, model, gen3_home(), clearance);
    // 8 capsules on 8 bodies: 28 pairs, 7 adjacent; the rest kept or named in the notes.
    int left_out = 0;
    for (const std::string& note : fit.notes) left_out += note.find("left out") != std::string::npos;
    EXPECT_EQ(fit.pairs + left_out, 21);
  }
  EXPECT_THROW((void)phri::fit_capsules(urdf, model, Eigen::VectorXd::Zero(3)), phri::ConfigError);
}

// Distance from p to the segment [a, b].
double segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (p - a - t * ab).norm();
}

TEST(CapsuleFit, CapsulesEncloseBoxesCylindersAndSpheres) {
  phri::test::GeneratedArm arm = phri::test::make_arm({.dof = 6, .prismatic_joint = -1, .gripper = false, .seed = 9});
  // Collision geometry on three links, placed and rotated; a mesh on a fourth.
  auto add = [&](const std::string& link, const std::string& geometry) {
    const std::string tag = "<link name=\"" + link + "\">";
    arm.urdf.insert(arm.urdf.find(tag) + tag.size(),
                    "<collision><origin xyz=\"0.01 -0.06 0.02\" rpy=\"0.4 -0.3 1.1\"/><geometry>" + geometry + "</geometry></collision>");
  };
  add("link_2", "<box size=\"0.06 0.2 0.08\"/>");
  add("link_3", "<cylinder radius=\"0.035\" length=\"0.18\"/>");
  add("link_4", "<sphere radius=\"0.05\"/>");
  add("link_5", "<mesh filename=\"package://nowhere/link_5.stl\"/>");
  phri::ModelOptions options;
  options.tip_link = "flange";
  const phri::Model model = phri::Model::from_urdf_string(arm.urdf, options);
  const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(arm.home_q.data(), 6);
  const phri::CapsuleFit fit = phri::fit_capsules(arm.urdf, model, home, {.link_frame_radius_m = 0.04, .clearance_m = 0.0});
  const phri::CollisionModel c = phri::CollisionModel::from_yaml_string(fit.yaml, model, "fitted");
  expect_pairs_valid(fit, model, home, 0.0);
  bool mesh_noted = false;
  for (const std::string& note : fit.notes) mesh_noted |= note.find("link_5") != std::string::npos;
  EXPECT_TRUE(mesh_noted);
  // Random points of each solid, in its own frame, then in the link (= body) frame.
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  origin.linear() = (Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX())).toRotationMatrix();
  origin.translation() << 0.01, -0.06, 0.02;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = -1.0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d box(0.03 * u(rng), 0.1 * u(rng), 0.04 * u(rng));
    const double a = M_PI * u(rng), r = 0.035 * std::sqrt(0.5 + 0.5 * u(rng));
    const Eigen::Vector3d cylinder(r * std::cos(a), r * std::sin(a), 0.09 * u(rng));
    const Eigen::Vector3d sphere = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 0.05 * std::cbrt(0.5 + 0.5 * u(rng));
    for (const auto& [link, local] : {std::pair{"link_2", box}, std::pair{"link_3", cylinder}, std::pair{"link_4", sphere}}) {
      const phri::Capsule* capsule = capsule_of(c, link);
      ASSERT_TRUE(capsule);
      const double outside = segment_distance(origin * local, capsule->p0, capsule->p1) - capsule->radius;
      EXPECT_LE(outside, 1e-10) << link;  // the YAML keeps 12 digits
      worst = std::max(worst, outside);
    }
  }
  EXPECT_LE(worst, 1e-10);  // the YAML keeps 12 digits
  // Tight on the cylinder: its radius, its length.
  const phri::Capsule* cylinder = capsule_of(c, "link_3");
  EXPECT_NEAR(cylinder->radius, 0.035, 1e-10);
  EXPECT_NEAR((cylinder->p1 - cylinder->p0).norm(), 0.18, 1e-9);
}

// A wrist whose axes meet (the 7-DoF arms' wrists): link_2's child joint sits at its origin and
// link_3 is the tip with no child joint. Every link with mass gets a capsule through its centre
// of mass (the COM the segment's middle), and the notes say what the link has.
TEST(CapsuleFit, EveryLinkWithMassIsCoveredIncludingAWristWhoseJointsMeet) {
  auto link = [](const std::string& name, double mass, const std::string& com) {
    return "<link name=\"" + name + "\"><inertial><origin xyz=\"" + com + "\"/><mass value=\"" + std::to_string(mass) +
           "\"/><inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>";
  };
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child, const std::string& xyz) {
    return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + child +
           "\"/><origin xyz=\"" + xyz + "\" rpy=\"1.5707963 0 0\"/><axis xyz=\"0 0 1\"/>"
           "<limit lower=\"-2\" upper=\"2\" effort=\"10\" velocity=\"1\"/></joint>";
  };
  const std::string urdf = "<robot name=\"wrist\">" + link("base_link", 2.0, "0 0 0.05") + link("link_1", 1.0, "0 0 0.1") +
                           link("link_2", 0.8, "0 0.03 0.04") + link("link_3", 0.5, "0 0 0.06") +
                           joint("joint_1", "base_link", "link_1", "0 0 0.1") + joint("joint_2", "link_1", "link_2", "0 0 0.3") +
                           joint("joint_3", "link_2", "link_3", "0 0 0") + "</robot>";
  const phri::Model model = phri::Model::from_urdf_string(urdf, {});
  const Eigen::VectorXd home = Eigen::VectorXd::Constant(3, 0.3);
  const phri::CapsuleFit fit = phri::fit_capsules(urdf, model, home, {.link_frame_radius_m = 0.04, .clearance_m = 0.0});
  for (const std::string& note : fit.notes) std::printf("note: %s\n", note.c_str());
  const phri::CollisionModel c = phri::CollisionModel::from_yaml_string(fit.yaml, model, "fitted");
  for (const auto& [name, com] : {std::pair{"link_2", Eigen::Vector3d(0, 0.03, 0.04)}, std::pair{"link_3", Eigen::Vector3d(0, 0, 0.06)}}) {
    const phri::Capsule* capsule = capsule_of(c, name);
    ASSERT_TRUE(capsule) << name;
    EXPECT_LT((0.5 * (capsule->p0 + capsule->p1) - com).norm(), 1e-12) << name;  // the COM in its middle
    EXPECT_LT(capsule->p0.norm(), 1e-12) << name;                                 // from the link's origin
  }
  ASSERT_TRUE(capsule_of(c, "link_1"));  // a child joint away from its origin: up to it, as before
  EXPECT_NEAR((capsule_of(c, "link_1")->p1 - Eigen::Vector3d(0, 0, 0.3)).norm(), 0.0, 1e-12);
  // True notes: link_2 has a child joint (at its origin), link_3 none.
  bool wrist_noted = false, tip_noted = false;
  for (const std::string& note : fit.notes) {
    EXPECT_EQ(note.find("no capsule"), std::string::npos) << note;
    if (note.find("'link_2'") != std::string::npos) wrist_noted = note.find("child joints at its origin") != std::string::npos;
    if (note.find("'link_3'") != std::string::npos) tip_noted = note.find("no child joint") != std::string::npos;
  }
  EXPECT_TRUE(wrist_noted);
  EXPECT_TRUE(tip_noted);
}

}  // namespace
