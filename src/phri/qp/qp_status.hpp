#pragma once
// phri::QpStatus: how a QpSolver::solve ended.
#include <string_view>

namespace phri {

enum class QpStatus {
  kOptimal,         // x is the minimiser; multipliers satisfy the KKT conditions
  kInfeasible,      // the constraints admit no point (x: last primal iterate)
  kIterationLimit,  // settings().max_iterations reached (x: last primal iterate)
  kInvalidInput,    // a data check failed, see QpSolver::invalid_reason() (x: zeros)
  kNumericalError,  // finite data whose iterates overflowed (x: zeros); not seen on sane data
};

constexpr std::string_view to_string(QpStatus status) {
  switch (status) {
    case QpStatus::kOptimal: return "optimal";
    case QpStatus::kInfeasible: return "infeasible";
    case QpStatus::kIterationLimit: return "iteration limit";
    case QpStatus::kInvalidInput: return "invalid input";
    case QpStatus::kNumericalError: return "numerical error";
  }
  return "unknown";
}

}  // namespace phri
