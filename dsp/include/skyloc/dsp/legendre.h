// Fully normalised associated Legendre functions
//
//   P̄_lm(x) = sqrt((2l+1)/(4π) · (l-m)!/(l+m)!) · P_lm(x),   0 ≤ m ≤ l,
//
// where P_lm carries the Condon–Shortley phase (-1)^m, as in Numerical Recipes' plgndr (the
// paper's reference [29]), Boost.Math legendre_p and std::sph_legendre. With this
// normalisation Y_lm = P̄_lm(cos θ)·e^{imφ} is the orthonormal complex harmonic, and
// P̄_l0² + 2 Σ_{m>0} P̄_lm² = (2l+1)/(4π) for every x (the addition theorem).
//
// Computed by the standard stable recursion in l for fixed m, seeded by the sectoral terms
//   P̄_00 = 1/sqrt(4π),  P̄_mm = -sqrt((2m+1)/(2m)) · sinθ · P̄_{m-1,m-1},
//   P̄_{m+1,m} = sqrt(2m+3) · x · P̄_mm,
//   P̄_lm = a_lm · (x·P̄_{l-1,m} - P̄_{l-2,m}/a_{l-1,m}),  a_lm = sqrt((4l²-1)/(l²-m²)),
// with the sectoral seeds carried in a scaled range (×1e-280 taken out at the end) so that
// sin^m θ does not underflow before the recursion in l has grown it back: accurate to
// ~1e-13 relative to sqrt((2l+1)/(4π)) for l up to kMaxShBands (tested at L = 256).
#pragma once

#include <cstddef>
#include <span>

namespace skyloc::dsp {

// Number of (l, m) pairs with 0 ≤ m ≤ l < bands.
constexpr std::size_t LegendreTriangleSize(int bands) {
  return static_cast<std::size_t>(bands) * static_cast<std::size_t>(bands + 1) / 2;
}
// Index of P̄_lm in a triangle: l(l+1)/2 + m.
constexpr std::size_t LegendreIndex(int l, int m) {
  return static_cast<std::size_t>(l) * static_cast<std::size_t>(l + 1) / 2 +
         static_cast<std::size_t>(m);
}

// Writes P̄_lm(cos θ) for 0 ≤ m ≤ l < bands at LegendreIndex(l, m). Both cos θ and sin θ are
// passed so that callers near the poles keep sin θ's full precision (sin θ ≥ 0). Returns
// false and writes nothing when bands < 1 or out.size() < LegendreTriangleSize(bands).
bool NormalisedLegendre(int bands, double cos_theta, double sin_theta, std::span<double> out);

}  // namespace skyloc::dsp
