// ctest-labels: unit
// The URDF cases that crashed, hung or silently corrupted the model (issue 16), each reproduced:
// kinematic loops (urdfdom 3 accepts them), an inertial urdfdom cannot parse (it zeroes the mass and
// goes on), inertias that break the triangle inequality (accepted with a warning), NaN moments, a
// missing inertial mid-chain, and a bad inertial on the fixed base link (ignored with a warning).
// References are independent of phri's loader: the URDF's own numbers and closed forms.
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>

#include "config_error.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

namespace {

using phri::test::expect_config_error;

const std::string kGen3Urdf = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf";

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string gen3_with(const std::string& from, const std::string& to) {
  std::string urdf = read_file(kGen3Urdf);
  const std::size_t at = urdf.find(from);
  if (at == std::string::npos) throw std::runtime_error("test setup: '" + from + "' not in gen3.urdf");
  urdf.replace(at, from.size(), to);
  return urdf;
}

std::string gen3_plus(const std::string& extra) {
  std::string urdf = read_file(kGen3Urdf);
  urdf.insert(urdf.rfind("</robot>"), extra);
  return urdf;
}

std::function<void()> loading(const std::string& urdf, const phri::ModelOptions& options = {}) {
  return [urdf, options] { (void)phri::Model::from_urdf_string(urdf, options, "bad.urdf"); };
}

const char* kInertial =
    "<inertial><mass value=\"0.5\"/><inertia ixx=\"1e-3\" ixy=\"0\" ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial>";

std::string link(const std::string& name) { return "<link name=\"" + name + "\">" + kInertial + "</link>"; }
std::string joint(const std::string& name, const std::string& parent, const std::string& child) {
  return "<joint name=\"" + name + "\" type=\"continuous\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><axis xyz=\"0 0 1\"/></joint>";
}

// The sum of every <mass value="..."> of a URDF text but the base link's: an independent count.
double moving_mass_in_text(const std::string& urdf, const std::string& base_link) {
  double total = 0.0;
  const std::regex link_re("<link name=\"([^\"]+)\">\\s*<inertial>[\\s\\S]*?<mass value=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), link_re); it != std::sregex_iterator(); ++it) {
    if ((*it)[1] != base_link) total += std::stod((*it)[2]);
  }
  return total;
}

// ------------------------------------------------------------------------------ kinematic loops
TEST(UrdfLoops, ALinkThatIsTheChildOfTwoJointsIsOneLineError) {
  const std::string urdf = "<robot name=\"loop\"><link name=\"a\"/>" + link("b") + link("c") + joint("j1", "a", "b") +
                           joint("j2", "b", "c") + joint("j3", "a", "c") + "</robot>";
  const auto error = expect_config_error(loading(urdf), {.element = "link 'c'", .mentions = {"j2", "j3", "kinematic loop"}});
  ASSERT_TRUE(error);
  EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos);
  phri::ModelOptions with_tip;  // the tip resolution walked parents for ever
  with_tip.tip_link = "c";
  expect_config_error(loading(urdf, with_tip), {.element = "link 'c'", .mentions = {"kinematic loop"}});
}

TEST(UrdfLoops, AJointWhoseParentIsItsChild) {
  const std::string urdf =
      "<robot name=\"loop\"><link name=\"a\"/>" + link("b") + joint("j1", "a", "b") + joint("j2", "b", "b") + "</robot>";
  expect_config_error(loading(urdf), {.element = "joint 'j2'", .mentions = {"'b'", "kinematic loop"}});
}

TEST(UrdfLoops, ACycleOfJointsAwayFromTheRoot) {
  // b and c are each other's parent: every link has one parent, the walk up never ends.
  const std::string urdf = "<robot name=\"loop\"><link name=\"a\"/>" + link("b") + link("c") + joint("j1", "b", "c") +
                           joint("j2", "c", "b") + "</robot>";
  expect_config_error(loading(urdf), {.mentions = {"kinematic loop"}});
}

TEST(UrdfLoops, TheGen3WithALoopAddedIsRefusedWhateverTheOptions) {
  const std::string urdf = gen3_plus(joint("closing", "bracelet_link", "shoulder_link"));
  expect_config_error(loading(urdf), {.element = "link 'shoulder_link'", .mentions = {"joint_1", "closing"}});
  phri::ModelOptions options;
  options.tip_link = "end_effector_link";
  options.locked_joints = {"closing"};
  expect_config_error(loading(urdf, options), {.mentions = {"kinematic loop"}});
}

// ------------------------------------------------------------------ what urdfdom cannot parse
TEST(UrdfParserMessages, AMassWithAUnitIsAnErrorNamingTheLink) {
  const std::string hand = "<link name=\"hand\"><inertial><mass value=\"0.73kg\"/><inertia ixx=\"1e-3\" ixy=\"0\" "
                           "ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial></link>"
                           "<joint name=\"hand_joint\" type=\"fixed\"><parent link=\"end_effector_link\"/>"
                           "<child link=\"hand\"/></joint>";
  expect_config_error(loading(gen3_plus(hand)), {.element = "link 'hand' <inertial>", .mentions = {"0.73kg"}});
  // Written correctly, the mass is there: the model's moving mass is the file's sum.
  std::string good_hand = hand;
  good_hand.replace(good_hand.find("0.73kg"), 6, "0.73");
  const std::string urdf = gen3_plus(good_hand);
  const phri::Model model = phri::Model::from_urdf_string(urdf);
  EXPECT_NEAR(model.total_mass(), moving_mass_in_text(urdf, "base_link"), 1e-12);
  EXPECT_NEAR(model.total_mass() - phri::Model::from_urdf_file(kGen3Urdf).total_mass(), 0.73, 1e-12);
}

TEST(UrdfParserMessages, NaNMomentsNameTheLinkNotPositiveDefiniteness) {
  for (const char* nan : {"nan", "NaN", "-nan"}) {
    const auto error = expect_config_error(loading(gen3_with("ixx=\"0.011088\"", std::string("ixx=\"") + nan + "\"")),
                                           {.mentions = {"half_arm_1_link"}});
    ASSERT_TRUE(error);
    EXPECT_EQ(std::string(error->what()).find("positive definite"), std::string::npos) << error->what();
  }
}

// --------------------------------------------------------------------------- odd inertias
// The manufacturer file: principal moments 0.00368 + 0.00796 < 0.01274, positive definite.
TEST(UrdfInertia, TriangleInequalityViolationIsAcceptedWithAWarningAndUsedAsGiven) {
  const std::string odd = "ixx=\"0.00368\" ixy=\"0\" ixz=\"0\" iyy=\"0.00796\" iyz=\"0\" izz=\"0.01274\"";
  const std::string urdf = gen3_with("ixx=\"0.011088\" ixy=\"5E-06\" ixz=\"0\" iyy=\"0.001072\" iyz=\"-0.000691\" izz=\"0.011255\"", odd);
  const phri::Model model = phri::Model::from_urdf_string(urdf, {}, "odd.urdf");
  ASSERT_EQ(model.warnings().size(), 1u);
  EXPECT_NE(model.warnings()[0].find("half_arm_1_link"), std::string::npos) << model.warnings()[0];
  EXPECT_NE(model.warnings()[0].find("triangle inequality"), std::string::npos);

  // Independent reference: the two models differ only in that link's rotational inertia, so
  // M_odd - M = Jw^T R (I_odd - I) R^T Jw, Jw the angular Jacobian of the link, R its world rotation
  // (the inertial origin has rpy 0 in the file).
  const phri::Model original = phri::Model::from_urdf_file(kGen3Urdf);
  EXPECT_TRUE(original.warnings().empty());
  phri::Data data(model), data_original(original);
  Eigen::VectorXd q(7);
  q << 0.3, -0.7, 1.1, 1.9, -0.4, 0.8, 0.2;
  phri::crba(model, data, q);
  phri::crba(original, data_original, q);
  phri::forward_kinematics(original, data_original, q);
  phri::update_frame_placements(original, data_original);
  const int frame = original.frame_id("half_arm_1_link");
  Eigen::MatrixXd jacobian(6, 7);
  phri::frame_jacobian(original, data_original, frame, phri::ReferenceFrame::kLocalWorldAligned, jacobian);
  Eigen::Matrix3d before, after;
  before << 0.011088, 5e-6, 0, 5e-6, 0.001072, -0.000691, 0, -0.000691, 0.011255;
  after = Eigen::Vector3d(0.00368, 0.00796, 0.01274).asDiagonal();
  const Eigen::Matrix3d r = data_original.frame_placements[static_cast<std::size_t>(frame)].linear();
  const Eigen::MatrixXd jw = jacobian.bottomRows(3);
  const Eigen::MatrixXd expected = jw.transpose() * r * (after - before) * r.transpose() * jw;
  EXPECT_LT((data.mass_matrix - data_original.mass_matrix - expected).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(UrdfInertia, TheGen3LoadsWithoutWarnings) {
  EXPECT_TRUE(phri::Model::from_urdf_file(kGen3Urdf).warnings().empty());
}

TEST(UrdfInertia, AnInvalidInertialOnTheFixedBaseIsIgnoredWithAWarning) {
  const phri::Model original = phri::Model::from_urdf_file(kGen3Urdf);
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"ixx=\"0.004622\"", "ixx=\"-0.004622\""},  // not positive definite
           {"<mass value=\"1.697\"", "<mass value=\"-1.697\""},
           {"<mass value=\"1.697\"", "<mass value=\"5000\""}}) {
    const phri::Model model = phri::Model::from_urdf_string(gen3_with(from, to));
    ASSERT_EQ(model.warnings().size(), 1u) << to;
    EXPECT_NE(model.warnings()[0].find("base_link"), std::string::npos) << model.warnings()[0];
    EXPECT_NE(model.warnings()[0].find("ignored"), std::string::npos) << model.warnings()[0];
    // Same dynamics as the clean file: the base link does not move.
    phri::Data a(model), b(original);
    Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(7, -1.0, 1.0), qd = Eigen::VectorXd::Constant(7, 0.5);
    phri::crba(model, a, q);
    phri::crba(original, b, q);
    EXPECT_EQ(a.mass_matrix, b.mass_matrix);
    EXPECT_EQ(phri::nonlinear_effects(model, a, q, qd), phri::nonlinear_effects(original, b, q, qd));
  }
}

// ------------------------------------------------------------------- missing inertial mid-chain
std::string without_inertial_of(std::string urdf, const std::string& link_name) {
  const std::size_t at = urdf.find("<link name=\"" + link_name + "\">");
  if (at == std::string::npos) throw std::runtime_error("test setup: no link " + link_name);
  const std::size_t begin = urdf.find("<inertial>", at);
  const std::size_t end = urdf.find("</inertial>", begin) + std::string("</inertial>").size();
  urdf.erase(begin, end - begin);
  return urdf;
}

TEST(UrdfInertia, AMissingInertialMidChainNamesTheLinkNotAMasslessJoint) {
  const std::string urdf = without_inertial_of(read_file(kGen3Urdf), "forearm_link");
  const auto error = expect_config_error(loading(urdf), {.element = "link 'forearm_link'", .mentions = {"no <inertial>", "joint_4"}});
  ASSERT_TRUE(error);
  EXPECT_EQ(std::string(error->what()).find("moves no mass"), std::string::npos) << error->what();
  // Nothing below joint_7 weighs anything: then the joint truly moves no mass.
  const std::string bare_end = without_inertial_of(read_file(kGen3Urdf), "bracelet_link");
  expect_config_error(loading(bare_end), {.element = "joint 'joint_7'", .mentions = {"moves no mass", "bracelet_link"}});
}

// ------------------------------------------------------------------------------- origins
// urdfdom turns rpy into a quaternion, finite for any finite angle: the numbers are checked as
// written (issue 37), each naming the joint or link and the attribute.
TEST(UrdfOrigins, AnRpyOf1e308IsRefusedNamingTheJoint) {
  expect_config_error(loading(gen3_with("rpy=\"1.5708 2.1343E-17 -1.1102E-16\"", "rpy=\"1e308 0 0\"")),
                      {.element = "joint 'joint_2' <origin> rpy", .mentions = {"1e+308", "beyond one turn"}, .file = "bad.urdf"});
}

TEST(UrdfOrigins, AnglesInDegreesAndHugeOffsetsAreRefused) {
  // An inertial's origin: the link is named.
  expect_config_error(loading(gen3_with("<origin xyz=\"-4.4E-05 -0.09958 -0.013278\" rpy=\"0 0 0\"/>",
                                        "<origin xyz=\"-4.4E-05 -0.09958 -0.013278\" rpy=\"0 90 0\"/>")),
                      {.element = "link 'half_arm_1_link' <origin> rpy", .mentions = {"90", "degrees"}});
  expect_config_error(loading(gen3_with("xyz=\"0 -0.21038 -0.006375\"", "xyz='0 -1e308 -0.006375'")),
                      {.element = "joint 'joint_3' <origin> xyz", .mentions = {"1e+308", "100 m"}});
}

// Finite but meaningless limits (NaN and infinity were already refused).
TEST(UrdfOrigins, LimitsBeyondAnyArmAreRefused) {
  const std::string limit = "<limit effort=\"39\" velocity=\"1.3963\"/>";
  ASSERT_NE(read_file(kGen3Urdf).find(limit), std::string::npos);
  expect_config_error(loading(gen3_with(limit, "<limit effort=\"39\" velocity=\"1e308\"/>")),
                      {.element = "joint 'joint_1' <limit>", .mentions = {"velocity 1e+308"}});
  expect_config_error(loading(gen3_with(limit, "<limit effort=\"1e308\" velocity=\"1.3963\"/>")),
                      {.element = "joint 'joint_1' <limit>", .mentions = {"effort 1e+308"}});
}

TEST(UrdfOrigins, RoundedTurnsAndCommentsAreNotNumbersToRefuse) {
  // 6.2832 is 2 pi rounded up; a comment's text is no origin.
  EXPECT_NO_THROW(phri::Model::from_urdf_string(
      gen3_with("rpy=\"1.5708 2.1343E-17 -1.1102E-16\"", "rpy=\"6.2832 0 -6.2832\"")));
  EXPECT_NO_THROW(phri::Model::from_urdf_string(gen3_plus("<!-- <origin rpy=\"1e308 0 0\"/> -->")));
}

}  // namespace
