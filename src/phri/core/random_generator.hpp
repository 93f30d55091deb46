#pragma once
// phri::RandomGenerator: a small, seeded, platform-independent pseudo-random generator for the
// simulator's noise and disturbances. The standard library's distributions are implementation-
// defined (libstdc++ and libc++ give different normals for the same engine), so the generator and
// the two distributions we need are written out here: xoshiro256** seeded through splitmix64, a
// uniform double on [0, 1) from the top 53 bits, and normals by the Box-Muller transform.
// Same seed and stream => bit-identical sequence on every platform with IEEE doubles and a
// correctly rounded libm (log, sqrt, sin, cos). No allocation, no global state.
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
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    // u1 in (0, 1] so that log(u1) is finite.
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }
  /// N(0, std^2); returns exactly 0 without drawing when std == 0, so a disabled noise source
  /// consumes nothing from the sequence.
  double normal(double std) { return std == 0.0 ? 0.0 : std * normal(); }

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
