// ctest-labels: unit
// The logged-QP file of the demo session (bench/data/demo_qps.bin, bench/data/README.md): phri's
// solver reproduces the recorded solutions from the recorded warm starts, and they satisfy the KKT
// conditions; the file's format round-trips and a truncated, corrupted or foreign file is a clear
// error.
#include <logged_qps.hpp>

#include <phri/core/error.hpp>

#include <qp_kkt.hpp>
#include <temp_dir.hpp>

#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace phri {
namespace {

const std::string kDemoFile = std::string(PHRI_SOURCE_DIR) + "/bench/data/demo_qps.bin";

std::vector<std::uint8_t> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const LoggedQps& demo() {
  static const LoggedQps qps = read_logged_qps(kDemoFile);
  return qps;
}

// About 300 ticks spread over the session, and every tick that changed the active set or ended
// with a constraint active (the others are unconstrained minima).
std::vector<std::size_t> sample(const LoggedQps& qps) {
  const auto active = [](QpActiveSide s) { return s != QpActiveSide::kInactive; };
  std::vector<std::size_t> ticks;
  const std::size_t step = std::max<std::size_t>(1, qps.ticks.size() / 300);
  for (std::size_t k = 0; k < qps.ticks.size(); ++k) {
    const LoggedQpTick& t = qps.ticks[k];
    if (k % step == 0 || t.iterations > 0 || std::ranges::any_of(t.final_rows, active) ||
        std::ranges::any_of(t.final_bounds, active)) {
      ticks.push_back(k);
    }
  }
  return ticks;
}

double max_relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return ((a - b).cwiseAbs().array() / (1.0 + b.cwiseAbs().array())).maxCoeff();
}

TEST(LoggedQps, DemoFileDescribesTheGen3Session) {
  const LoggedQps& qps = demo();
  EXPECT_EQ(qps.n, 7);
  EXPECT_EQ(qps.m_eq, 0);
  EXPECT_GT(qps.m_in, 7);  // the torque rows and the self-collision pairs
  ASSERT_GE(qps.stride, 1u);
  EXPECT_EQ(qps.ticks.size(), (qps.session_solves + qps.stride - 1) / qps.stride);
  EXPECT_LE(qps.session_solves, qps.session_cycles);
  EXPECT_GT(qps.session_cycles, 30000u);  // the ~35 s demo at 1 kHz
  for (std::size_t k = 1; k < qps.ticks.size(); ++k) ASSERT_LT(qps.ticks[k - 1].cycle, qps.ticks[k].cycle);
}

// The same solver on the same data from the same start: the same x. Across builds (another -march,
// the sanitizer build) floating-point contraction may differ in the last bits, hence a tolerance.
TEST(LoggedQps, SolverReproducesTheRecordedSolutionsWhichSatisfyKkt) {
  const LoggedQps& qps = demo();
  QpSolver solver(qps.n, qps.m_eq, qps.m_in);
  solver.settings() = qps.settings;
  QpSolver cold(qps.n, qps.m_eq, qps.m_in);
  cold.settings() = qps.settings;
  int exact = 0, checked = 0;
  for (const std::size_t k : sample(qps)) {
    const LoggedQpTick& tick = qps.ticks[k];
    const std::string what = "tick " + std::to_string(k) + " (cycle " + std::to_string(tick.cycle) + ")";
    ASSERT_EQ(solver.solve(tick.problem, prepare_replay(tick, solver, true)), tick.status) << what;
    ASSERT_EQ(tick.status, QpStatus::kOptimal) << what;
    EXPECT_LE(max_relative_difference(solver.x(), tick.x), 1e-9) << what;
    exact += solver.x() == tick.x ? 1 : 0;
    EXPECT_TRUE(std::ranges::equal(solver.active_rows(), tick.final_rows)) << what;
    EXPECT_TRUE(std::ranges::equal(solver.active_bounds(), tick.final_bounds)) << what;
    ++checked;
    const test::Kkt kkt = test::kkt_residuals(tick.problem, solver);
    EXPECT_LE(kkt.stationarity, 1e-9) << what;
    EXPECT_LE(kkt.primal, 1e-9) << what;
    EXPECT_LE(kkt.dual, 1e-9) << what;
    EXPECT_LE(kkt.complementarity, 1e-9) << what;
    // H positive definite: one minimiser, whatever the start.
    cold.solve(tick.problem, prepare_replay(tick, cold, false));
    EXPECT_LE(max_relative_difference(cold.x(), tick.x), 1e-7) << what << ", cold";
  }
  RecordProperty("ticks_checked", checked);
  RecordProperty("bit_identical", exact);
  EXPECT_GT(checked, 250);
}

// A small file of every kind of entry (an equality row, absent sides, both options, every status
// and side) comes back bit for bit.
TEST(LoggedQps, RoundTripsEveryField) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  LoggedQps qps;
  qps.n = 3;
  qps.m_eq = 1;
  qps.m_in = 2;
  qps.settings.max_iterations = 17;
  qps.settings.feasibility_tolerance = 3e-11;
  qps.session_cycles = 10;
  qps.session_solves = 9;
  qps.stride = 3;
  for (std::uint32_t t = 0; t < 3; ++t) {
    LoggedQpTick& tick = qps.ticks.emplace_back();
    tick.cycle = 3 * t + 1;
    tick.options = {.warm_start = t != 1, .reuse_hessian_factor = t == 2};
    tick.solves = static_cast<std::uint8_t>(t + 1);
    tick.status = static_cast<QpStatus>(t);
    tick.iterations = static_cast<std::int32_t>(10 * t);
    tick.warm_rows = {QpActiveSide::kLower, QpActiveSide::kUpper};
    tick.warm_bounds = {QpActiveSide::kInactive, QpActiveSide::kUpper, QpActiveSide::kLower};
    tick.final_rows = {QpActiveSide::kInactive, QpActiveSide::kLower};
    tick.final_bounds = {QpActiveSide::kUpper, QpActiveSide::kInactive, QpActiveSide::kInactive};
    tick.problem.resize(3, 1, 2);
    tick.problem.H = Eigen::Matrix3d::Random().triangularView<Eigen::Lower>();
    tick.problem.g = Eigen::Vector3d::Random();
    tick.problem.A_eq = Eigen::RowVector3d::Random();
    tick.problem.b_eq << 0.1 * t;
    tick.problem.A = Eigen::Matrix<double, 2, 3>::Random();
    tick.problem.l << -kInf, -1.0 / 3.0;
    tick.problem.u << 2.0, kInf;
    tick.problem.lb << -1e20, -kInf, -std::numeric_limits<double>::denorm_min();
    tick.problem.ub << 1e20, kInf, std::numeric_limits<double>::max();
    tick.x = Eigen::Vector3d::Random();
  }
  const std::string path = test::temp_path("phri_test_logged_qps", "round_trip.bin");
  write_logged_qps(path, qps, 3);
  const LoggedQps back = read_logged_qps(path);
  EXPECT_EQ(back.n, 3);
  EXPECT_EQ(back.m_eq, 1);
  EXPECT_EQ(back.m_in, 2);
  EXPECT_EQ(back.settings.max_iterations, 17);
  EXPECT_EQ(back.settings.feasibility_tolerance, 3e-11);
  EXPECT_EQ(back.settings.infinity, qps.settings.infinity);
  EXPECT_EQ(back.session_cycles, 10u);
  EXPECT_EQ(back.session_solves, 9u);
  EXPECT_EQ(back.stride, 3u);
  ASSERT_EQ(back.ticks.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const LoggedQpTick& a = qps.ticks[k];
    const LoggedQpTick& b = back.ticks[k];
    EXPECT_EQ(b.cycle, a.cycle);
    EXPECT_EQ(b.options.warm_start, a.options.warm_start);
    EXPECT_EQ(b.options.reuse_hessian_factor, a.options.reuse_hessian_factor);
    EXPECT_EQ(b.solves, a.solves);
    EXPECT_EQ(b.status, a.status);
    EXPECT_EQ(b.iterations, a.iterations);
    EXPECT_EQ(b.warm_rows, a.warm_rows);
    EXPECT_EQ(b.warm_bounds, a.warm_bounds);
    EXPECT_EQ(b.final_rows, a.final_rows);
    EXPECT_EQ(b.final_bounds, a.final_bounds);
    EXPECT_EQ(b.problem.H, a.problem.H);
    EXPECT_EQ(b.problem.g, a.problem.g);
    EXPECT_EQ(b.problem.A_eq, a.problem.A_eq);
    EXPECT_EQ(b.problem.b_eq, a.problem.b_eq);
    EXPECT_EQ(b.problem.A, a.problem.A);
    EXPECT_EQ(b.problem.l, a.problem.l);
    EXPECT_EQ(b.problem.u, a.problem.u);
    EXPECT_EQ(b.problem.lb, a.problem.lb);
    EXPECT_EQ(b.problem.ub, a.problem.ub);
    EXPECT_EQ(b.x, a.x);
  }
}

// The message of parse_logged_qps on `bytes` (empty when it does not throw IoError).
std::string parse_error(const std::vector<std::uint8_t>& bytes) {
  try {
    parse_logged_qps(bytes, "the file");
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

// The demo file's payload changed by `edit`, compressed again.
std::vector<std::uint8_t> edited_file(const std::function<void(std::vector<std::uint8_t>&)>& edit) {
  const std::vector<std::uint8_t> file = file_bytes(kDemoFile);
  std::vector<std::uint8_t> payload(ZSTD_getFrameContentSize(file.data(), file.size()));
  EXPECT_EQ(ZSTD_decompress(payload.data(), payload.size(), file.data(), file.size()), payload.size());
  edit(payload);
  std::vector<std::uint8_t> out(ZSTD_compressBound(payload.size()));
  out.resize(ZSTD_compress(out.data(), out.size(), payload.data(), payload.size(), 1));
  return out;
}

TEST(LoggedQps, TruncatedCorruptedOrForeignFilesAreClearErrors) {
  const std::vector<std::uint8_t> file = file_bytes(kDemoFile);
  ASSERT_GT(file.size(), 1000u);
  EXPECT_NE(parse_error({file.begin(), file.begin() + static_cast<long>(file.size() / 2)}).find("truncated or corrupted"),
            std::string::npos);
  EXPECT_NE(parse_error({file.begin(), file.begin() + 6}).find("truncated or corrupted"), std::string::npos);
  std::vector<std::uint8_t> flipped = file;
  flipped[file.size() / 2] ^= 0x10;
  EXPECT_NE(parse_error(flipped).find("truncated or corrupted"), std::string::npos);
  EXPECT_NE(parse_error({'h', 'e', 'l', 'l', 'o'}).find("not a logged-QP file"), std::string::npos);

  constexpr std::size_t kVersionOffset = 8, kTicksOffset = 24;
  const std::string version = parse_error(edited_file([](auto& p) { p[kVersionOffset] = 2; }));
  EXPECT_NE(version.find("format version 2, this build reads version 1"), std::string::npos) << version;
  const std::string magic = parse_error(edited_file([](auto& p) { p[0] = 'X'; }));
  EXPECT_NE(magic.find("not a logged-QP file"), std::string::npos) << magic;
  const std::string sizes = parse_error(edited_file([](auto& p) { ++p[kTicksOffset]; }));
  EXPECT_NE(sizes.find("sizes do not add up"), std::string::npos) << sizes;
  const std::string cut = parse_error(edited_file([](auto& p) { p.resize(p.size() - 8); }));
  EXPECT_NE(cut.find("sizes do not add up"), std::string::npos) << cut;
  EXPECT_THROW(read_logged_qps(kDemoFile + ".absent"), IoError);
}

}  // namespace
}  // namespace phri
