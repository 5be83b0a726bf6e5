// Heading from two horizon strips (horizon_strip.h) by circular cross-correlation: the
// second way skyloc recovers how far a robot is turned from a taught view, beside 1D
// SURF's RANSAC displacement (surf1d.h). It uses every column, not only blobs, so it
// needs no features and answers on a bland skyline; it assumes the two strips differ by a
// turn (a shift) and little else, which holds for a robot back on its taught route.
//
//   c(s) = sum_j (a_j - mean a) (b_(j+s mod n) - mean b) / (n std a std b)
//
// is the normalised (Pearson) correlation of the stored strip a with the test strip b
// shifted back by s columns, for every s = 0..n-1 (O(n^2): two passes of 130 k multiply-adds
// at n = 360, one for the peak and one for the runner-up; allocation-free, so it can run per
// frame). The best s is refined to a fraction of a column by the parabola through c(s-1), c(s),
// c(s+1). The test strip's content is then turned by +s columns from the stored one:
// heading_offset_deg = s * 360 / n, wrapped to [-180, 180), the convention of
// LandmarkMatch::heading_offset_deg (a robot that turned by +psi about body z sees its scene turned
// by -psi). The peak's correlation is the confidence (1: identical up to the turn; near 0:
// unrelated), and the best correlation outside +-min_peak_separation columns of the peak says
// whether the turn is ambiguous (a periodic skyline).
#pragma once

#include <cstdint>
#include <span>

namespace skyloc::dsp {

enum class StripAlignmentError : std::uint8_t {
  kOk,
  kSizeMismatch,  // the strips differ in length, or are shorter than 3 columns
  kFlat,          // a strip is constant: no turn can be read from it
};

// A sentence naming the problem and the fix.
const char* StripAlignmentErrorMessage(StripAlignmentError error);

struct StripAlignment {
  double shift_columns = 0.0;       // test content relative to stored, (-n/2, n/2]
  double heading_offset_deg = 0.0;  // the same in degrees, [-180, 180)
  float correlation = 0.0f;         // c at the best whole-column shift, -1..1
  float runner_up = 0.0f;           // best c further than min_peak_separation from it
};

// min_peak_separation: columns around the peak that belong to it (its width), >= 1.
StripAlignmentError AlignStrips(std::span<const float> stored, std::span<const float> test,
                                StripAlignment* result, int min_peak_separation = 5);

}  // namespace skyloc::dsp
