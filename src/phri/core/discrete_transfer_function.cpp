#include <phri/core/discrete_transfer_function.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <phri/core/error.hpp>

namespace phri {

DiscreteTransferFunction::DiscreteTransferFunction(std::span<const double> numerator,
                                                   std::span<const double> denominator) {
  if (numerator.empty() || denominator.empty()) throw ConfigError("transfer function", "coefficients", "empty coefficients");
  if (numerator.size() > kMaxOrder + 1 || denominator.size() > kMaxOrder + 1) {
    throw ConfigError("transfer function", "coefficients", "order above 5");
  }
  const double a0 = denominator[0];
  if (a0 == 0.0 || !std::isfinite(a0)) throw ConfigError("transfer function", "coefficients", "a0 must be non-zero");
  b_.fill(0.0);
  a_.fill(0.0);
  for (std::size_t i = 0; i < numerator.size(); ++i) {
    if (!std::isfinite(numerator[i])) throw ConfigError("transfer function", "coefficients", "coefficient not finite");
    b_[i] = numerator[i] / a0;
  }
  for (std::size_t i = 0; i < denominator.size(); ++i) {
    if (!std::isfinite(denominator[i])) throw ConfigError("transfer function", "coefficients", "coefficient not finite");
    a_[i] = denominator[i] / a0;
  }
  order_ = static_cast<int>(std::max(numerator.size(), denominator.size())) - 1;
  reset();
}

DiscreteTransferFunction DiscreteTransferFunction::kinova_high_velocity() {
  // Muraccioli et al., section "Low-level Control", H_tf(z) (coefficients read through the Kortex API).
  return DiscreteTransferFunction({0.020175, -0.036975, 0.016917}, {1.0, -1.975063, 0.97518});
}

double DiscreteTransferFunction::dc_gain() const {
  double nb = 0.0;
  double na = 0.0;
  for (int i = 0; i <= order_; ++i) {
    nb += b_[static_cast<std::size_t>(i)];
    na += a_[static_cast<std::size_t>(i)];
  }
  return nb / na;
}

void DiscreteTransferFunction::reset_to_steady_state(double input) {
  // At rest x = u, y = G u for all k: state_i = sum_{j > i} (b_j u - a_j y).
  const double output = dc_gain() * input;
  for (int i = order_ - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    state_[k] = b_[k + 1] * input - a_[k + 1] * output + (i + 1 < order_ ? state_[k + 1] : 0.0);
  }
}

double DiscreteTransferFunction::largest_pole_magnitude(std::span<const double> denominator) {
  const auto n = static_cast<Eigen::Index>(denominator.size()) - 1;
  if (n < 1) return 0.0;
  // Companion matrix of the monic z^n + c1 z^(n-1) + ... + cn, c_i = a_i / a0.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) companion(0, i) = -denominator[static_cast<std::size_t>(i + 1)] / denominator[0];
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
  return solver.eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace phri
