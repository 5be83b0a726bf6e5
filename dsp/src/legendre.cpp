#include "skyloc/dsp/legendre.h"

#include <cmath>
#include <numbers>

namespace skyloc::dsp {

bool NormalisedLegendre(int bands, double cos_theta, double sin_theta, std::span<double> out) {
  if (bands < 1 || out.size() < LegendreTriangleSize(bands))
    return false;
  // The sectoral terms shrink like sin^m θ; carrying them ×1e280 keeps them representable
  // until the recursion in l has grown them back (true values below ~1e-588 become 0).
  constexpr double kScale = 1e280;
  constexpr double kUnscale = 1e-280;
  const double x = cos_theta;
  double sectoral = kScale / std::sqrt(4.0 * std::numbers::pi);  // scaled P̄_mm
  for (int m = 0; m < bands; ++m) {
    if (m > 0) {
      const double md = m;
      sectoral *= -std::sqrt((2.0 * md + 1.0) / (2.0 * md)) * sin_theta;
    }
    out[LegendreIndex(m, m)] = sectoral * kUnscale;
    if (m + 1 >= bands)
      continue;
    double p_prev = sectoral;
    double p = std::sqrt(2.0 * m + 3.0) * x * sectoral;
    out[LegendreIndex(m + 1, m)] = p * kUnscale;
    const double m2 = static_cast<double>(m) * m;
    for (int l = m + 2; l < bands; ++l) {
      const double l2 = static_cast<double>(l) * l;
      const double lm1 = l - 1.0;
      const double a = std::sqrt((4.0 * l2 - 1.0) / (l2 - m2));
      const double b = std::sqrt((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0));
      const double p_next = a * (x * p - b * p_prev);
      p_prev = p;
      p = p_next;
      out[LegendreIndex(l, m)] = p * kUnscale;
    }
  }
  return true;
}

}  // namespace skyloc::dsp
