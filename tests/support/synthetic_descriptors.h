// Synthetic vanilla-like descriptors for the batch SeqSLAM tests and benchmarks (we have
// no Nordland frames): place p of a route is value noise that changes smoothly over
// `smooth` places (neighbours look alike, as consecutive frames do), each group of 64
// values z-scored as the vanilla descriptor's 8x8 patches are. A query run revisits place
// floor(start + v t) with uniform noise added before the z-scoring. Stateless per row, so
// a 30,000-frame run can be produced row by row (and quantised) without keeping floats.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace skyloc::testing {

inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Uniform in [-1, 1) from a hash of (a, b, seed).
inline float HashUniform(std::uint64_t a, std::uint64_t b, std::uint64_t seed) {
  const std::uint64_t h = SplitMix64(SplitMix64(SplitMix64(seed) ^ a) ^ b);
  return static_cast<float>(static_cast<double>(h >> 11) * 0x1p-52 - 1.0);
}

struct SyntheticRoute {
  int dim = 2048;
  int smooth = 8;  // places over which the scene changes completely
  std::uint64_t seed = 1;

  // Place p seen by a query: `noise` (0 for the reference run) is the amplitude of the
  // uniform noise added per element, drawn from (noise_key, element).
  void Row(double place, float noise, std::uint64_t noise_key, std::span<float> out) const {
    const double cell = place / smooth;
    const auto k = static_cast<std::uint64_t>(std::floor(cell));
    const auto f = static_cast<float>(cell - std::floor(cell));
    for (std::size_t i = 0; i < out.size(); ++i) {
      const float a = HashUniform(k, i, seed), b = HashUniform(k + 1, i, seed);
      out[i] = a + (b - a) * f;
      if (noise > 0.0f)
        out[i] += noise * HashUniform(noise_key, i, seed + 0x5EEDu);
    }
    // z-score each group of 64 values (sample std), as patch normalisation.
    for (std::size_t g = 0; g < out.size(); g += 64) {
      const std::size_t e = std::min(out.size(), g + 64);
      double sum = 0, sq = 0;
      for (std::size_t i = g; i < e; ++i)
        sum += static_cast<double>(out[i]);
      const double mean = sum / static_cast<double>(e - g);
      for (std::size_t i = g; i < e; ++i)
        sq += (static_cast<double>(out[i]) - mean) * (static_cast<double>(out[i]) - mean);
      const double sd = e - g > 1 ? std::sqrt(sq / static_cast<double>(e - g - 1)) : 0.0;
      for (std::size_t i = g; i < e; ++i)
        out[i] = sd > 0 ? static_cast<float>((static_cast<double>(out[i]) - mean) / sd) : 0.0f;
    }
  }

  std::vector<float> Reference(int n) const {
    std::vector<float> v(static_cast<std::size_t>(n) * static_cast<std::size_t>(dim));
    for (int r = 0; r < n; ++r)
      Row(r, 0.0f, 0, RowSpan(v, r));
    return v;
  }
  // Query frame t at place floor(start + v t), clamped to the route [0, n_ref).
  std::vector<float> Query(int n, int n_ref, double start, double v, float noise,
                           std::vector<int>* truth = nullptr) const {
    std::vector<float> out(static_cast<std::size_t>(n) * static_cast<std::size_t>(dim));
    for (int t = 0; t < n; ++t) {
      const int p = std::min(n_ref - 1, static_cast<int>(std::floor(start + v * t)));
      Row(p, noise, static_cast<std::uint64_t>(t) + 1, RowSpan(out, t));
      if (truth != nullptr)
        truth->push_back(p);
    }
    return out;
  }
  std::span<float> RowSpan(std::vector<float>& v, int r) const {
    return std::span<float>(v).subspan(static_cast<std::size_t>(r) * static_cast<std::size_t>(dim),
                                       static_cast<std::size_t>(dim));
  }
};

}  // namespace skyloc::testing
