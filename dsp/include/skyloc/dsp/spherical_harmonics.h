// Real spherical harmonics, the projection of a sampled sky mask onto them (paper eq. 2) and
// the rotation-invariant amplitude spectrum (eq. 3). docs/SPHERICAL_HARMONICS.md has the
// conventions, the accuracy and the speed.
//
// The basis is eq. (1) of Stone et al. 2016, orthonormal on the sphere:
//   y_lm(θ, φ) = √2 · P̄_l|m|(cos θ) · cos(|m|φ)   m > 0
//              = √2 · P̄_l|m|(cos θ) · sin(|m|φ)   m < 0
//              =      P̄_l0(cos θ)                 m = 0
// with P̄ from legendre.h (normalisation N_lm folded in, Condon–Shortley phase included, as
// in the paper's reference [29]). Equivalently y_lm = √2·Re Y_l^m (m > 0), √2·Im Y_l^|m|
// (m < 0), Y_l^0 (m = 0) for the standard complex Y_l^m. The amplitudes do not depend on
// the sign convention; individual coefficients do.
//
// Coefficients of bands l = 0..L-1 are stored flat, L² of them, at k = l² + l + m.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/ring_fft.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::dsp {

constexpr std::size_t ShCoefficientCount(int bands) {
  return static_cast<std::size_t>(bands) * static_cast<std::size_t>(bands);
}
// k = l² + l + m for -l ≤ m ≤ l.
constexpr std::size_t ShIndex(int l, int m) {
  return static_cast<std::size_t>(l * l + l + m);
}

// All y_lm(θ, φ) for l < bands into out (≥ ShCoefficientCount(bands) values), using
// legendre_scratch (≥ LegendreTriangleSize(bands) values). Start-up and test use: double
// precision, no allocation. Returns false and writes nothing on a short span or bad bands.
bool RealSphericalHarmonics(int bands, double cos_theta, double sin_theta, double phi,
                            std::span<double> legendre_scratch, std::span<double> out);

// The fast projection c_lm = Σ_samples w·f·y_lm: a real FFT of every ring (RingFft, eight
// rings per SIMD pass) gives w_i·Σ_j f_ij·cos(mφ_j) and w_i·Σ_j f_ij·sin(mφ_j); for each m a
// small product of a precomputed float table √2·P̄_lm(cos θ_i) (rings × l, zero-padded;
// rings whose values are all below 1e-9 neither stored nor read) with those ring sums gives all l
// at once, accumulated in registers. Cost O(rings·longitudes·log longitudes + rings·L²), against
// the naive O(samples·L²). On grids with fewer than 2L-1 longitudes the m > longitudes/2 terms
// alias exactly as the naive sum does (FFT bin m mod longitudes, conjugated past Nyquist).
class ShProjector {
 public:
  // Builds the Legendre table for the grid's rings and the FFT tables (allocates; call at
  // start-up). The grid must stay alive only during Init.
  ShError Init(const ShGrid& grid, int bands);

  int bands() const { return bands_; }
  std::size_t sample_count() const {
    return static_cast<std::size_t>(rings_) * static_cast<std::size_t>(longitudes_);
  }
  std::size_t coefficient_count() const { return ShCoefficientCount(bands_); }

  // samples: sample_count() values in the grid's ring-major order (sky 1, ground 0, or any
  // real function). coeffs: coefficient_count() values. Allocates nothing.
  ShError Project(std::span<const float> samples, std::span<float> coeffs);

 private:
  // A run of 8 or 16 consecutive l of one m: the unit of the Legendre sum, accumulated in
  // registers over the rings where the table is not negligible.
  struct MBlock {
    int m = 0;
    int l_begin = 0;     // first l of the block
    int width = 0;       // 8 or 16 (the table is zero-padded past l = L-1)
    int first_ring = 0;  // rings outside [first_ring, end_ring) hold only |P̄| < 1e-9
    int end_ring = 0;
    std::size_t table_offset = 0;  // of P̄(ring first_ring, l_begin) in table_
    std::size_t stride = 0;        // floats from one ring to the next: the block's width
  };

  int bands_ = 0;
  int rings_ = 0;
  int longitudes_ = 0;
  RingFft fft_;  // scales ring i by its quadrature weight
  // Per block, in blocks_' order: its significant rings × width values, √2 folded in for
  // m > 0; one sequential read a frame.
  std::vector<float> table_;
  std::vector<MBlock> blocks_;   // in m order, then l order
  std::vector<int> bin_;         // FFT bin of each m (m mod longitudes, folded)
  std::vector<float> bin_sign_;  // -1 where the fold conjugates (sin terms change sign)
  std::vector<float> cos_sums_;  // bins × rings: w_i · Σ_j f cos(kφ_j)
  std::vector<float> sin_sums_;  // bins × rings: w_i · Σ_j f sin(kφ_j)
};

// The reference: the paper's O(samples · L²) method, a table Y[k][s] = y_k(direction s)
// (float, L² × samples) times the weighted sample vector, accumulated in double. Used by the
// tests and as the benchmark baseline. The table is capped at kMaxNaiveTableEntries.
class ShNaiveProjector {
 public:
  static constexpr std::size_t kMaxNaiveTableEntries = std::size_t{64} << 20;  // 256 MB

  ShError Init(const ShGrid& grid, int bands);
  int bands() const { return bands_; }
  std::size_t sample_count() const { return samples_; }
  std::size_t coefficient_count() const { return ShCoefficientCount(bands_); }
  ShError Project(std::span<const float> samples, std::span<float> coeffs);

 private:
  int bands_ = 0;
  std::size_t samples_ = 0;
  std::vector<float> table_;           // row k holds y_k at every sample
  std::vector<double> sample_weight_;  // quadrature weight of each sample
  std::vector<double> weighted_;       // w·f for the current call
};

enum class AmplitudeNormalisation : std::uint8_t {
  kNone,        // a_l as in eq. (3)
  kDivideByA0,  // a_l / a_0: a_0 = sky solid angle / sqrt(4π), so this removes sky size
  kUnitL2,      // a / ||a||_2: scale-free, for cosine-like comparisons with L1/L2
};

// The name the configuration file and the route database's messages use.
constexpr const char* AmplitudeNormalisationName(AmplitudeNormalisation normalisation) {
  switch (normalisation) {
    case AmplitudeNormalisation::kNone:
      return "none";
    case AmplitudeNormalisation::kDivideByA0:
      return "divide_by_a0";
    case AmplitudeNormalisation::kUnitL2:
      return "unit_l2";
  }
  return "?";
}

// a_l = sqrt(Σ_m c_lm²) for l = 0..bands-1 (eq. 3), then the normalisation. A zero spectrum
// (no sky) stays zero under either normalisation. coeffs: ShCoefficientCount(bands) values,
// amplitudes: bands values. Allocates nothing.
ShError AmplitudeSpectrum(std::span<const float> coeffs, int bands, std::span<float> amplitudes,
                          AmplitudeNormalisation normalisation = AmplitudeNormalisation::kNone);

enum class DescriptorMetric : std::uint8_t {
  kL1,      // Σ|a_i - b_i| (default: what SeqSLAM's difference matrix sums)
  kL2,      // sqrt(Σ (a_i - b_i)²)
  kCosine,  // 1 - a·b / (|a||b|); 0 when both are zero, 1 when only one is
};

// Distance between two descriptors of equal length; NaN when the lengths differ.
float DescriptorDistance(std::span<const float> a, std::span<const float> b,
                         DescriptorMetric metric = DescriptorMetric::kL1);

}  // namespace skyloc::dsp
