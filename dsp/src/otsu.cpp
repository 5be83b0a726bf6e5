#include "skyloc/dsp/otsu.h"

namespace skyloc::dsp {

OtsuResult OtsuThreshold(const Histogram256& histogram) {
  // Integer sums: exact for any image up to 2^32 pixels, so the maximiser is the same on
  // every architecture. Ties resolve to the lowest threshold.
  std::uint64_t total = 0;
  std::uint64_t weighted_total = 0;
  for (int v = 0; v < 256; ++v) {
    total += histogram[static_cast<std::size_t>(v)];
    weighted_total += static_cast<std::uint64_t>(v) * histogram[static_cast<std::size_t>(v)];
  }
  OtsuResult result;
  if (total == 0)
    return result;

  const double n = static_cast<double>(total);
  const double mean = static_cast<double>(weighted_total) / n;
  double total_variance = 0.0;
  for (int v = 0; v < 256; ++v) {
    const double d = v - mean;
    total_variance += d * d * histogram[static_cast<std::size_t>(v)];
  }
  total_variance /= n;

  std::uint64_t count_low = 0;
  std::uint64_t weighted_low = 0;
  double best = -1.0;
  for (int t = 0; t < 255; ++t) {
    count_low += histogram[static_cast<std::size_t>(t)];
    weighted_low += static_cast<std::uint64_t>(t) * histogram[static_cast<std::size_t>(t)];
    const std::uint64_t count_high = total - count_low;
    if (count_low == 0 || count_high == 0)
      continue;
    const double w0 = static_cast<double>(count_low) / n;
    const double w1 = static_cast<double>(count_high) / n;
    const double mu0 = static_cast<double>(weighted_low) / static_cast<double>(count_low);
    const double mu1 =
        static_cast<double>(weighted_total - weighted_low) / static_cast<double>(count_high);
    const double between = w0 * w1 * (mu0 - mu1) * (mu0 - mu1);
    if (between > best) {
      best = between;
      result.threshold = t;
    }
  }
  if (best > 0.0 && total_variance > 0.0)
    result.separability = best / total_variance;
  return result;
}

}  // namespace skyloc::dsp
