#include "skyloc/dsp/otsu.h"

#include <cmath>

namespace skyloc::dsp {
namespace {

struct Totals {
  std::uint64_t count = 0;
  std::uint64_t weighted = 0;
  double mean = 0.0;
  double variance = 0.0;
};

// Integer sums: exact for any image up to 2^32 pixels, so the same on every architecture.
Totals TotalsOf(const Histogram256& histogram) {
  Totals t;
  for (int v = 0; v < 256; ++v) {
    t.count += histogram[static_cast<std::size_t>(v)];
    t.weighted += static_cast<std::uint64_t>(v) * histogram[static_cast<std::size_t>(v)];
  }
  if (t.count == 0)
    return t;
  const double n = static_cast<double>(t.count);
  t.mean = static_cast<double>(t.weighted) / n;
  for (int v = 0; v < 256; ++v) {
    const double d = v - t.mean;
    t.variance += d * d * histogram[static_cast<std::size_t>(v)];
  }
  t.variance /= n;
  return t;
}

// The result for the split with `count_low` pixels (weighted sum `weighted_low`) at or
// below `threshold`.
OtsuResult Split(const Totals& t, int threshold, std::uint64_t count_low,
                 std::uint64_t weighted_low) {
  OtsuResult r;
  r.threshold = threshold;
  const std::uint64_t count_high = t.count - count_low;
  if (count_low == 0 || count_high == 0)
    return r;
  const double n = static_cast<double>(t.count);
  const double w0 = static_cast<double>(count_low) / n;
  const double w1 = static_cast<double>(count_high) / n;
  r.low_mean = static_cast<double>(weighted_low) / static_cast<double>(count_low);
  r.high_mean = static_cast<double>(t.weighted - weighted_low) / static_cast<double>(count_high);
  const double between = w0 * w1 * (r.high_mean - r.low_mean) * (r.high_mean - r.low_mean);
  if (t.variance > 0.0)
    r.separability = between / t.variance;
  const double within = t.variance - between;
  r.within_sigma = std::sqrt((within > 0.0 ? within : 0.0) + 1.0 / 12.0);
  return r;
}

}  // namespace

OtsuResult OtsuThreshold(const Histogram256& histogram) {
  const Totals t = TotalsOf(histogram);
  if (t.count == 0)
    return {};
  // Ties resolve to the lowest threshold.
  std::uint64_t count_low = 0;
  std::uint64_t weighted_low = 0;
  double best = -1.0;
  int best_threshold = 0;
  std::uint64_t best_count = 0, best_weighted = 0;
  const double n = static_cast<double>(t.count);
  for (int th = 0; th < 255; ++th) {
    count_low += histogram[static_cast<std::size_t>(th)];
    weighted_low += static_cast<std::uint64_t>(th) * histogram[static_cast<std::size_t>(th)];
    const std::uint64_t count_high = t.count - count_low;
    if (count_low == 0 || count_high == 0)
      continue;
    const double w0 = static_cast<double>(count_low) / n;
    const double w1 = static_cast<double>(count_high) / n;
    const double mu0 = static_cast<double>(weighted_low) / static_cast<double>(count_low);
    const double mu1 =
        static_cast<double>(t.weighted - weighted_low) / static_cast<double>(count_high);
    const double between = w0 * w1 * (mu0 - mu1) * (mu0 - mu1);
    if (between > best) {
      best = between;
      best_threshold = th;
      best_count = count_low;
      best_weighted = weighted_low;
    }
  }
  if (best < 0.0)
    return {};  // a single grey level: nothing to split
  return Split(t, best_threshold, best_count, best_weighted);
}

bool SeparatesSkyFromGround(const OtsuResult& split) {
  if (split.within_sigma <= 0.0)
    return false;  // an empty class
  const double separation = split.high_mean - split.low_mean;
  return separation >= kMinClassSeparationLevels &&
         separation >= kMinClassSeparationSigmas * split.within_sigma;
}

}  // namespace skyloc::dsp
