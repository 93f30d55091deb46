#pragma once
// phri::RandomGenerator: a small, seeded, platform-independent pseudo-random generator for the
// simulator's noise and disturbances. The standard library's distributions are implementation-
// defined (libstdc++ and libc++ give different normals for the same engine), so the generator and
// the two distributions we need are written out here: xoshiro256** seeded through splitmix64, a
// uniform double on [0, 1) from the top 53 bits, and normals by the Box-Muller transform.
// Same seed and stream => bit-identical sequence on every platform with IEEE doubles and a
// correctly rounded libm (log, sqrt; sine and cosine are batch_math's). No allocation, no global state.
#include <phri/core/batch_math.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace phri {

class RandomGenerator {
public:
  /// `stream` separates independent sequences drawn from one user seed (e.g. one per noise source),
  /// so that turning one source off does not shift the numbers of the others.
  explicit RandomGenerator(std::uint64_t seed = 0, std::uint64_t stream = 0) { reseed(seed, stream); }

  void reseed(std::uint64_t seed, std::uint64_t stream = 0) {
    std::uint64_t x = seed ^ (0x9E3779B97F4A7C15ULL * (stream + 1));
    for (auto& s : state_) s = splitmix64(x);
    has_spare_ = false;
  }

  /// Next raw 64-bit value (xoshiro256**).
  std::uint64_t next() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  /// Uniform on [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform on [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal N(0, 1) (Box-Muller; the second value of each pair is kept for the next call).
  double normal() {
    double x;
    fill_normal(&x, 1);
    return x;
  }
  /// N(0, std^2); returns exactly 0 without drawing when std == 0, so a disabled noise source
  /// consumes nothing from the sequence.
  double normal(double std) { return std == 0.0 ? 0.0 : std * normal(); }
  /// `count` standard normals, the same sequence as `count` calls of normal(), their angles' sines
  /// and cosines taken up to batch_math::kWidth at a time (a simulator step draws one or two per joint).
  void fill_normal(double* out, int count) {
    int k = 0;
    if (has_spare_ && count > 0) {
      out[k++] = spare_;
      has_spare_ = false;
    }
    constexpr int kWidth = batch_math::kWidth;
    double radius[kWidth], angle[kWidth], sine[kWidth], cosine[kWidth];
    while (k < count) {
      const int pairs = std::min(kWidth, (count - k + 1) / 2);
      for (int j = 0; j < pairs; ++j) {
        const double u1 = 1.0 - uniform();  // in (0, 1], so that log(u1) is finite
        const double u2 = uniform();
        radius[j] = std::sqrt(-2.0 * std::log(u1));
        angle[j] = 2.0 * std::numbers::pi * u2;
      }
      batch_math::sincos(angle, pairs, sine, cosine);
      for (int j = 0; j < pairs; ++j) {
        out[k++] = radius[j] * cosine[j];
        if (k < count) {
          out[k++] = radius[j] * sine[j];
        } else {
          spare_ = radius[j] * sine[j];
          has_spare_ = true;
        }
      }
    }
  }

private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static std::uint64_t splitmix64(std::uint64_t& x) {
    std::uint64_t z = (x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

  std::uint64_t state_[4] = {0, 0, 0, 0};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace phri
