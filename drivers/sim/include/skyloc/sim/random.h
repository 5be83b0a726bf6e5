// A deterministic random source written out here rather than <random>'s distributions,
// whose output differs between standard libraries: the simulator promises byte-identical
// images for the same seed on every build.
#pragma once

#include <cstdint>

namespace skyloc::sim {

// One SplitMix64 step from state `x`: the output a generator seeded with `x` gives first.
// Also a stateless hash of one integer (street heights, per-pixel noise).
inline std::uint64_t SplitMix64(std::uint64_t x) {
  std::uint64_t z = x + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// SplitMix64 of `x` mapped to [0, 1).
inline double SplitMix64Unit(std::uint64_t x) {
  return static_cast<double>(SplitMix64(x) >> 11) * 0x1.0p-53;
}

// SplitMix64 (Steele, Lea, Flood 2014): tiny state, good enough for scenery and noise.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}

  std::uint64_t Next() {
    const std::uint64_t z = SplitMix64(state_);
    state_ += 0x9E3779B97F4A7C15ull;
    return z;
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Approximately standard normal (sum of four uniforms, variance scaled to 1): cheap and
  // bounded, which is what sensor noise wants.
  // The draws are separate statements: the operands of one + are evaluated in an
  // unspecified order, and the sum's rounding depends on which draw comes first.
  double Normal() {
    const double u0 = Uniform();
    const double u1 = Uniform();
    const double u2 = Uniform();
    const double u3 = Uniform();
    const double s = u0 + u1 + u2 + u3 - 2.0;
    return s * 1.7320508075688772;  // sqrt(12 / 4)
  }

 private:
  std::uint64_t state_;
};

// Stateless hash of integer coordinates to [0, 1): procedural textures and clouds.
inline float HashToUnit(std::int32_t x, std::int32_t y, std::int32_t z, std::uint32_t seed) {
  std::uint32_t h = seed * 0x9E3779B1u;
  h ^= static_cast<std::uint32_t>(x) * 0x85EBCA77u;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<std::uint32_t>(y) * 0xC2B2AE3Du;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<std::uint32_t>(z) * 0x27D4EB2Fu;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

}  // namespace skyloc::sim
