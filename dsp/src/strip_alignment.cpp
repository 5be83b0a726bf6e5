#include "skyloc/dsp/strip_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace skyloc::dsp {

const char* StripAlignmentErrorMessage(StripAlignmentError error) {
  switch (error) {
    case StripAlignmentError::kOk:
      return "ok";
    case StripAlignmentError::kSizeMismatch:
      return "the two horizon strips differ in length (or are shorter than 3 columns): "
             "extract both with the same HorizonStripOptions";
    case StripAlignmentError::kFlat:
      return "a horizon strip is constant, so no turn can be read from it: check the "
             "strip's elevation band sees the skyline";
  }
  return "unknown strip alignment error";
}

namespace {

// sum_j a_j b_j in double over four running sums: one long chain of dependent additions
// waits on the adder's latency at every term; four interleaved ones keep it busy (~3x
// faster per frame here), and double keeps the sum exact enough for the mean correction.
double Dot(std::span<const float> a, std::span<const float> b) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  const std::size_t n = a.size();
  std::size_t j = 0;
  for (; j + 4 <= n; j += 4) {
    s0 += static_cast<double>(a[j]) * static_cast<double>(b[j]);
    s1 += static_cast<double>(a[j + 1]) * static_cast<double>(b[j + 1]);
    s2 += static_cast<double>(a[j + 2]) * static_cast<double>(b[j + 2]);
    s3 += static_cast<double>(a[j + 3]) * static_cast<double>(b[j + 3]);
  }
  for (; j < n; ++j)
    s0 += static_cast<double>(a[j]) * static_cast<double>(b[j]);
  return (s0 + s1) + (s2 + s3);
}

}  // namespace

StripAlignmentError AlignStrips(std::span<const float> stored, std::span<const float> test,
                                StripAlignment* result, int min_peak_separation,
                                std::span<double> scratch) {
  const std::size_t n = stored.size();
  if (n < 3 || test.size() != n)
    return StripAlignmentError::kSizeMismatch;
  // Means and deviations in double: the strips are sums of many pixels.
  double mean_a = 0, mean_b = 0;
  for (std::size_t j = 0; j < n; ++j) {
    mean_a += static_cast<double>(stored[j]);
    mean_b += static_cast<double>(test[j]);
  }
  mean_a /= static_cast<double>(n);
  mean_b /= static_cast<double>(n);
  double var_a = 0, var_b = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double da = static_cast<double>(stored[j]) - mean_a;
    var_a += da * da;
    const double db = static_cast<double>(test[j]) - mean_b;
    var_b += db * db;
  }
  if (!(var_a > 0) || !(var_b > 0))
    return StripAlignmentError::kFlat;
  const double norm = 1.0 / std::sqrt(var_a * var_b);

  // With the means taken out afterwards, sum_j (a_j - ma)(b_(j+s) - mb) = sum_j a_j b_(j+s) -
  // n ma mb, so each c(s) is a plain dot product in two pieces, with no modulo in the inner
  // loop: this runs on every matched frame.
  const double mean_product = static_cast<double>(n) * mean_a * mean_b;
  auto correlation = [&](std::size_t s) {
    const std::size_t wrap = n - s;
    return (Dot(stored.first(wrap), test.subspan(s)) + Dot(stored.subspan(wrap), test.first(s)) -
            mean_product) *
           norm;
  };
  // With n values of scratch, every c(s) is computed once and the runner-up read back;
  // without, a second pass recomputes them (allocation-free for any n). Same values either
  // way: c(s) is the same arithmetic each time.
  const bool keep = scratch.size() >= n;
  std::size_t best = 0;
  double best_c = -2, sum_squares = 0;
  for (std::size_t s = 0; s < n; ++s) {
    const double c = correlation(s);
    if (keep)
      scratch[s] = c;
    sum_squares += c * c;
    if (c > best_c) {
      best_c = c;
      best = s;
    }
  }
  auto at = [&](std::size_t s) { return keep ? scratch[s] : correlation(s); };
  const std::size_t separation =
      static_cast<std::size_t>(min_peak_separation < 1 ? 1 : min_peak_separation);
  // The runner-up is any c away from the peak (on a wide peak, its own flank); the second
  // peak is the best other local maximum, the competing turn. Neighbours are looked at only
  // for a value that would raise it, so the pass without scratch stays near one pass.
  double runner_up = -1, second_peak = -1;
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t d = s > best ? s - best : best - s;
    if (std::min(d, n - d) <= separation)
      continue;
    const double c = at(s);
    runner_up = std::max(runner_up, c);
    if (c > second_peak && c >= at((s + n - 1) % n) && c >= at((s + 1) % n))
      second_peak = c;
  }
  const double left = at((best + n - 1) % n);
  const double right = at((best + 1) % n);
  const double curvature = left - 2 * best_c + right;
  double offset = 0;
  if (curvature < 0)
    offset = std::clamp(0.5 * (left - right) / curvature, -0.5, 0.5);
  double shift = static_cast<double>(best) + offset;
  if (shift > static_cast<double>(n) / 2)
    shift -= static_cast<double>(n);
  double degrees = shift * 360.0 / static_cast<double>(n);
  if (degrees >= 180)
    degrees -= 360;
  if (degrees < -180)
    degrees += 360;
  result->shift_columns = shift;
  result->heading_offset_deg = degrees;
  result->correlation = static_cast<float>(best_c);
  result->runner_up = static_cast<float>(runner_up);
  result->second_peak = static_cast<float>(second_peak);
  result->noise = static_cast<float>(std::sqrt(sum_squares / static_cast<double>(n)));
  return StripAlignmentError::kOk;
}

}  // namespace skyloc::dsp
