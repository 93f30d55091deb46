#pragma once
// Sine and cosine of a batch of arguments at once, for the hot loops: the forward kinematics' joint
// angles and the simulator's Gaussian noise (Box-Muller's angles). libm's sincos is one call of
// ~15-20 ns per angle; this loop has no calls and no branches, so the compiler runs it four angles to
// an AVX2 register. Within an ulp or two of libm (test: BatchMath.*); angles outside the reduced
// range go to libm. (A batch log was tried for Box-Muller's radius: slower than libm's, whose log is
// a few ns.)
//
// x = k pi/2 + r with |r| <= pi/4 (Cody-Waite: pi/2 in three parts, the first two of 33
// bits, so k P1 and k P2 are exact for |k| < 2^20), then Taylor polynomials of r to degree 15 (sin)
// and 16 (cos): the first omitted terms, r^17/17! and r^18/18!, are below 5e-17 at pi/4.
#include <cmath>
#include <cstdint>
#include <cstring>

namespace phri::batch_math {

constexpr double kReducibleRad = 1.0e5;  ///< sincos: |k| < 2^17, the reduction is exact

/// The most arguments one call takes.
constexpr int kWidth = 8;

/// s[i] = sin(x[i]) and c[i] = cos(x[i]) for i < n <= kWidth.
inline void sincos(const double* x, int n, double* s, double* c) {
  constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
  constexpr double kP1 = 0x1.921fb544p+0;       // pi/2, its first 33 bits
  constexpr double kP2 = 0x1.0b4611a6p-34;      // the next 33
  constexpr double kP3 = 0x1.3198a2e037073p-69;  // the rest, rounded
  constexpr double kRound = 0x1.8p52;           // adding it rounds to an integer (|v| < 2^51)
  double in[kWidth] = {};
  for (int i = 0; i < n; ++i) in[i] = x[i];
  double out_s[kWidth], out_c[kWidth];
  for (int i = 0; i < kWidth; ++i) {
    const double v = in[i];
    const double shifted = v * kTwoOverPi + kRound;
    std::uint64_t bits;
    std::memcpy(&bits, &shifted, sizeof bits);
    const double k = shifted - kRound;
    const double r = ((v - k * kP1) - k * kP2) - k * kP3;
    const double r2 = r * r;
    const double sin_r =
        r + r * r2 *
                (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
                 r2 * (1.0 / 6227020800 + r2 * (-1.0 / 1307674368000.0)))))));
    const double cos_r =
        1.0 + r2 * (-0.5 + r2 * (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 +
              r2 * (1.0 / 479001600 + r2 * (-1.0 / 87178291200.0 + r2 * (1.0 / 20922789888000.0))))))));
    // Quadrant k mod 4: 1 and 3 swap sine and cosine; sin < 0 in 2, 3; cos < 0 in 1, 2.
    const std::uint64_t quadrant = bits & 3u;
    const double sine = (quadrant & 1u) != 0 ? cos_r : sin_r;
    const double cosine = (quadrant & 1u) != 0 ? sin_r : cos_r;
    out_s[i] = (quadrant & 2u) != 0 ? -sine : sine;
    out_c[i] = ((quadrant + 1u) & 2u) != 0 ? -cosine : cosine;
  }
  bool reducible = true;
  for (int i = 0; i < n; ++i) {
    s[i] = out_s[i];
    c[i] = out_c[i];
    reducible &= std::abs(in[i]) <= kReducibleRad;
  }
  if (reducible) return;
  for (int i = 0; i < n; ++i) {
    if (std::abs(in[i]) <= kReducibleRad) continue;
    s[i] = std::sin(in[i]);  // large, infinite or NaN
    c[i] = std::cos(in[i]);
  }
}

}  // namespace phri::batch_math
