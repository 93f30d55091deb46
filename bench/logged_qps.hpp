#pragma once
// The logged-QP file (format: bench/data/README.md): the QPs the controller solved in a session,
// each with the warm-start active set it started from, the options it was solved with and the
// solution it found. phri_record_qps (bench/record_qps.cpp) writes it, phri_bench's LoggedQpReplay
// replays it (bench/bench_logged_qps.cpp), tests/test_logged_qps.cpp checks it.
#include <phri/qp/qp_problem.hpp>
#include <phri/qp/qp_settings.hpp>
#include <phri/qp/qp_solve_options.hpp>
#include <phri/qp/qp_solver.hpp>
#include <phri/qp/qp_status.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace phri {

struct LoggedQpTick {
  std::uint32_t cycle = 0;   ///< the session's control cycle (0: the first)
  QpSolveOptions options;    ///< as the controller passed them to QpSolver::solve
  std::uint8_t solves = 1;   ///< solves in that cycle; > 1: a constraint was relaxed and this is the last (cold) one
  QpStatus status = QpStatus::kOptimal;
  std::int32_t iterations = 0;  ///< active-set changes (QpSolver::iterations)
  std::vector<QpActiveSide> warm_rows, warm_bounds;    ///< the solver's active set before the solve
  std::vector<QpActiveSide> final_rows, final_bounds;  ///< after it
  QpProblem problem;  ///< as solved (only H's lower triangle is stored: the upper part reads 0)
  Eigen::VectorXd x;  ///< the solution
};

struct LoggedQps {
  static constexpr std::uint32_t kVersion = 1;
  Eigen::Index n = 0, m_eq = 0, m_in = 0;
  QpSettings settings;                ///< the solver's settings in the session
  std::uint32_t session_cycles = 0;   ///< control cycles of the session
  std::uint32_t session_solves = 0;   ///< cycles that solved a QP
  std::uint32_t stride = 1;           ///< every stride-th of them is recorded, from the first
  std::vector<LoggedQpTick> ticks;
};

/// Writes `qps` as one zstd frame (with its checksum) at `zstd_level`. Throws phri::IoError.
void write_logged_qps(const std::string& path, const LoggedQps& qps, int zstd_level);
/// Reads the file; throws phri::IoError naming the file and what is wrong with it: not a zstd
/// frame, truncated or corrupted (zstd's error, its checksum), another format version, or sizes
/// that do not add up.
LoggedQps read_logged_qps(const std::string& path);
/// The same from the file's bytes (`name` for the messages).
LoggedQps parse_logged_qps(const std::vector<std::uint8_t>& file_bytes, const std::string& name);

/// Puts `solver` (sized n, m_eq, m_in; the file's settings) where the controller's solver was
/// before `tick`'s solve: the recorded warm-start set, and the Hessian factor (from the tick's own
/// H, the controller's of that cycle) when the tick reused it. Returns the options to solve
/// tick.problem with: the recorded ones, warm_start cleared when not `warm`.
QpSolveOptions prepare_replay(const LoggedQpTick& tick, QpSolver& solver, bool warm);

}  // namespace phri
