#include "skyloc/dsp/strip_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

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
    case StripAlignmentError::kNoStored:
      return "the strip correlator holds no stored strip: call Init, then SetStored with "
             "the route frame's strip, before Align";
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

// A strip's mean and sum of squared deviations, in double: the strips are sums of many
// pixels.
struct Moments {
  double mean = 0;
  double var = 0;
};

Moments MomentsOf(std::span<const float> x) {
  Moments m;
  for (const float v : x)
    m.mean += static_cast<double>(v);
  m.mean /= static_cast<double>(x.size());
  for (const float v : x) {
    const double d = static_cast<double>(v) - m.mean;
    m.var += d * d;
  }
  return m;
}

// c(s) as the definition gives it, one dot product: with the means taken out afterwards,
// sum_j (a_j - ma)(b_(j+s) - mb) = sum_j a_j b_(j+s) - n ma mb, in two pieces with no
// modulo in the inner loop.
struct DirectCorrelation {
  std::span<const float> stored;
  std::span<const float> test;
  double mean_product;  // n ma mb
  double norm;          // 1 / sqrt(var a var b)

  DirectCorrelation(std::span<const float> a, std::span<const float> b, const Moments& ma,
                    const Moments& mb)
      : stored(a),
        test(b),
        mean_product(static_cast<double>(a.size()) * ma.mean * mb.mean),
        norm(1.0 / std::sqrt(ma.var * mb.var)) {}

  double operator()(std::size_t s) const {
    const std::size_t wrap = stored.size() - s;
    return (Dot(stored.first(wrap), test.subspan(s)) + Dot(stored.subspan(wrap), test.first(s)) -
            mean_product) *
           norm;
  }
};

// Reads the alignment off c(s) (at(s) for s = 0..n-1), its maximum c(best) and the sum of
// its squares: the runner-up, the second peak, the parabola's fraction of a column and the
// turn in degrees.
template <typename At>
void ReadAlignment(std::size_t n, std::size_t best, double best_c, double sum_squares,
                   int min_peak_separation, const At& at, StripAlignment* result) {
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
}

}  // namespace

StripAlignmentError AlignStrips(std::span<const float> stored, std::span<const float> test,
                                StripAlignment* result, int min_peak_separation,
                                std::span<double> scratch) {
  const std::size_t n = stored.size();
  if (n < 3 || test.size() != n)
    return StripAlignmentError::kSizeMismatch;
  const Moments ma = MomentsOf(stored), mb = MomentsOf(test);
  if (!(ma.var > 0) || !(mb.var > 0))
    return StripAlignmentError::kFlat;
  const DirectCorrelation correlation(stored, test, ma, mb);
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
  ReadAlignment(
      n, best, best_c, sum_squares, min_peak_separation,
      [&](std::size_t s) { return keep ? scratch[s] : correlation(s); }, result);
  return StripAlignmentError::kOk;
}

bool StripCorrelator::Init(int columns) {
  columns_ = 0;
  has_stored_ = false;
  if (columns < 3)
    return false;
  const auto n = static_cast<std::size_t>(columns);
  stored_.assign(n, 0.0f);
  stored_spectrum_.assign(n / 2 + 1, Complex());
  spectrum_.assign(n / 2 + 1, Complex());
  deviations_.assign(n, 0.0);
  correlation_.assign(n, 0.0);
  // Half spectra both ways, and no 1/n on the inverse (it is in the normalisation).
  fft_.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  fft_.SetFlag(Eigen::FFT<double>::Unscaled);
  // kissfft makes a length's plan, twiddles and work buffers on its first use: one
  // transform each way here, so Align allocates nothing.
  fft_.fwd(spectrum_.data(), deviations_.data(), static_cast<Eigen::Index>(n));
  fft_.inv(correlation_.data(), spectrum_.data(), static_cast<Eigen::Index>(n));
  columns_ = columns;
  return true;
}

StripAlignmentError StripCorrelator::SetStored(std::span<const float> stored) {
  const auto n = static_cast<std::size_t>(columns_);
  if (n == 0)
    return StripAlignmentError::kNoStored;
  if (stored.size() != n)
    return StripAlignmentError::kSizeMismatch;
  std::copy(stored.begin(), stored.end(), stored_.begin());
  has_stored_ = true;
  const Moments m = MomentsOf(stored);
  stored_mean_ = m.mean;
  stored_var_ = m.var;
  stored_flat_ = !(m.var > 0);
  if (stored_flat_)
    return StripAlignmentError::kFlat;
  for (std::size_t j = 0; j < n; ++j)
    deviations_[j] = static_cast<double>(stored[j]) - m.mean;
  fft_.fwd(stored_spectrum_.data(), deviations_.data(), static_cast<Eigen::Index>(n));
  return StripAlignmentError::kOk;
}

bool StripCorrelator::Holds(std::span<const float> stored) const {
  return has_stored_ && stored.size() == stored_.size() &&
         std::memcmp(stored.data(), stored_.data(), stored_.size() * sizeof(float)) == 0;
}

StripAlignmentError StripCorrelator::Align(std::span<const float> test, StripAlignment* result,
                                           int min_peak_separation) {
  const auto n = static_cast<std::size_t>(columns_);
  if (n == 0 || !has_stored_)
    return StripAlignmentError::kNoStored;
  if (test.size() != n)
    return StripAlignmentError::kSizeMismatch;
  const Moments mb = MomentsOf(test);
  if (stored_flat_ || !(mb.var > 0))
    return StripAlignmentError::kFlat;
  for (std::size_t j = 0; j < n; ++j)
    deviations_[j] = static_cast<double>(test[j]) - mb.mean;
  fft_.fwd(spectrum_.data(), deviations_.data(), static_cast<Eigen::Index>(n));

  // The cross spectrum conj(A) B, and Parseval's sum of |A|^2 |B|^2 over the full
  // spectrum: bins 1..(n-1)/2 stand for their mirror images too, bin 0 and (n even) bin
  // n/2 for themselves.
  const std::size_t bins = n / 2 + 1;
  double power = 0;
  for (std::size_t k = 0; k < bins; ++k) {
    const Complex a = stored_spectrum_[k], b = spectrum_[k];
    const double re = a.real() * b.real() + a.imag() * b.imag();
    const double im = a.real() * b.imag() - a.imag() * b.real();
    spectrum_[k] = Complex(re, im);
    const double weight = (k == 0 || 2 * k == n) ? 1.0 : 2.0;
    power += weight * (re * re + im * im);
  }
  fft_.inv(correlation_.data(), spectrum_.data(), static_cast<Eigen::Index>(n));
  const double var_product = stored_var_ * mb.var;
  const double scale = 1.0 / (static_cast<double>(n) * std::sqrt(var_product));
  double fft_max = -2;
  for (std::size_t s = 0; s < n; ++s) {
    correlation_[s] *= scale;
    fft_max = std::max(fft_max, correlation_[s]);
  }
  const double sum_squares = power / (static_cast<double>(n) * var_product);

  // The peak as AlignStrips finds it: every shift that may be the maximum, computed again
  // by the definition (the transforms' error is ~1e-15, far inside kCandidate), then the
  // first of the largest.
  constexpr double kCandidate = 1e-9;
  const DirectCorrelation direct(stored_, test, Moments{stored_mean_, stored_var_}, mb);
  std::size_t best = 0;
  double best_c = -2;
  for (std::size_t s = 0; s < n; ++s) {
    if (correlation_[s] < fft_max - kCandidate)
      continue;
    correlation_[s] = direct(s);
    if (correlation_[s] > best_c) {
      best_c = correlation_[s];
      best = s;
    }
  }
  correlation_[(best + n - 1) % n] = direct((best + n - 1) % n);
  correlation_[(best + 1) % n] = direct((best + 1) % n);
  ReadAlignment(
      n, best, best_c, sum_squares, min_peak_separation,
      [&](std::size_t s) { return correlation_[s]; }, result);
  return StripAlignmentError::kOk;
}

}  // namespace skyloc::dsp
