#pragma once
// phri::QpInvalidReason: which input check made QpSolver return QpStatus::kInvalidInput.
// QpSolver::invalid_index() names the offending row, variable or pivot.
#include <string_view>

namespace phri {

enum class QpInvalidReason {
  kNone,
  kDimensionMismatch,           // problem sizes differ from resize(), or the solver was never resized
  kNonFiniteHessian,            // NaN/Inf in H (index: row)
  kHessianNotPositiveDefinite,  // Cholesky pivot too small (index: pivot)
  kMissingHessianFactor,        // reuse_hessian_factor without a valid stored factor
  kInvalidHessianFactor,        // set_hessian_factor: NaN/Inf or non-positive diagonal (index: row)
  kNonFiniteGradient,           // NaN/Inf in g (index: entry)
  kNonFiniteEqualityRows,       // NaN/Inf in A_eq (index: row)
  kNonFiniteEqualityTarget,     // NaN/Inf in b_eq (index: entry)
  kNonFiniteInequalityRows,     // NaN/Inf in A (index: row)
  kInvalidRowBound,             // NaN in l or u, l = +inf or u = -inf (index: row)
  kRowBoundsInverted,           // l > u (index: row)
  kInvalidVariableBound,        // NaN in lb or ub, lb = +inf or ub = -inf (index: variable)
  kVariableBoundsInverted,      // lb > ub (index: variable)
};

constexpr std::string_view to_string(QpInvalidReason reason) {
  switch (reason) {
    case QpInvalidReason::kNone: return "none";
    case QpInvalidReason::kDimensionMismatch: return "dimension mismatch";
    case QpInvalidReason::kNonFiniteHessian: return "non-finite H";
    case QpInvalidReason::kHessianNotPositiveDefinite: return "H not positive definite";
    case QpInvalidReason::kMissingHessianFactor: return "no stored Hessian factor to reuse";
    case QpInvalidReason::kInvalidHessianFactor: return "invalid Hessian factor";
    case QpInvalidReason::kNonFiniteGradient: return "non-finite g";
    case QpInvalidReason::kNonFiniteEqualityRows: return "non-finite A_eq";
    case QpInvalidReason::kNonFiniteEqualityTarget: return "non-finite b_eq";
    case QpInvalidReason::kNonFiniteInequalityRows: return "non-finite A";
    case QpInvalidReason::kInvalidRowBound: return "NaN or wrong-signed infinity in l/u";
    case QpInvalidReason::kRowBoundsInverted: return "l > u";
    case QpInvalidReason::kInvalidVariableBound: return "NaN or wrong-signed infinity in lb/ub";
    case QpInvalidReason::kVariableBoundsInverted: return "lb > ub";
  }
  return "unknown";
}

}  // namespace phri
