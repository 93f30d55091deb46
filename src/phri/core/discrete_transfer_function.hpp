#pragma once
// phri::DiscreteTransferFunction: a SISO z-domain filter
//
//            b0 + b1 z^-1 + ... + bn z^-n
//   H(z) = --------------------------------,   n <= kMaxOrder (5, as Kortex's ControlLoopParameters)
//            1  + a1 z^-1 + ... + an z^-n
//
// in transposed direct form II, with fixed-size state (no allocation). The Kinova "torque high
// velocity" filter of the paper (section "Low-level Control") is kinova_high_velocity().
// Coefficients are given with a0; they are normalised by it.
#include <array>
#include <initializer_list>
#include <span>

namespace phri {

class DiscreteTransferFunction {
public:
  static constexpr int kMaxOrder = 5;

  /// Identity filter (y = x).
  DiscreteTransferFunction() = default;
  /// numerator = {b0, b1, ...}, denominator = {a0, a1, ...}; a0 != 0, at most kMaxOrder + 1 entries
  /// each. Throws phri::ConfigError otherwise (configuration time only).
  DiscreteTransferFunction(std::span<const double> numerator, std::span<const double> denominator);
  DiscreteTransferFunction(std::initializer_list<double> numerator, std::initializer_list<double> denominator)
      : DiscreteTransferFunction(std::span<const double>(numerator.begin(), numerator.size()),
                                 std::span<const double>(denominator.begin(), denominator.size())) {}

  /// The paper's identified Kinova filter H(z) = (0.020175 - 0.036975 z^-1 + 0.016917 z^-2) /
  /// (1 - 1.975063 z^-1 + 0.97518 z^-2), at the 1 kHz Kortex cycle (paper eq. in section
  /// "Low-level Control"; DC gain 0.000117/0.000117 = 1, high-frequency gain ~0.019).
  static DiscreteTransferFunction kinova_high_velocity();

  /// One sample: y[k] from x[k].
  double step(double input) {
    const double output = b_[0] * input + state_[0];
    for (int i = 0; i < order_; ++i) {
      state_[static_cast<std::size_t>(i)] = b_[static_cast<std::size_t>(i + 1)] * input -
                                            a_[static_cast<std::size_t>(i + 1)] * output +
                                            (i + 1 < order_ ? state_[static_cast<std::size_t>(i + 1)] : 0.0);
    }
    return output;
  }
  /// Zero state (as if the input and output had always been 0).
  void reset() { state_.fill(0.0); }
  /// State of a filter at rest with constant input `input` (output dc_gain() * input).
  void reset_to_steady_state(double input);

  int order() const { return order_; }
  /// H(1) = sum(b) / sum(a).
  double dc_gain() const;
  const std::array<double, kMaxOrder + 1>& numerator() const { return b_; }
  const std::array<double, kMaxOrder + 1>& denominator() const { return a_; }

  /// Largest pole magnitude of a denominator {a0, a1, ..., an} (a0 != 0): the roots of
  /// a0 z^n + a1 z^(n-1) + ... + an, as the eigenvalues of its companion matrix. The filter is
  /// stable when it is < 1 (every pole inside the unit circle); 0 for a constant denominator.
  static double largest_pole_magnitude(std::span<const double> denominator);

private:
  int order_ = 0;
  std::array<double, kMaxOrder + 1> b_{1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  std::array<double, kMaxOrder + 1> a_{1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  std::array<double, kMaxOrder> state_{};
};

}  // namespace phri
