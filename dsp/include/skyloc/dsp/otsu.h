// Otsu's threshold (Otsu 1979): the grey level that maximises the between-class variance
// of a 256-bin histogram. The paper segments sky from ground with it (section III-A).
#pragma once

#include <array>
#include <cstdint>

namespace skyloc::dsp {

using Histogram256 = std::array<std::uint32_t, 256>;

struct OtsuResult {
  // Pixels with value > threshold are the bright class (sky).
  int threshold = 0;
  // Between-class variance at the threshold, divided by the total variance (0..1):
  // near 1 for a clean bimodal image, near 0 when there is nothing to separate.
  double separability = 0.0;
};

// An empty or single-valued histogram has nothing to separate: threshold 0, separability 0.
OtsuResult OtsuThreshold(const Histogram256& histogram);

}  // namespace skyloc::dsp
