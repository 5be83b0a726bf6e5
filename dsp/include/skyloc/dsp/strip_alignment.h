// Heading from two horizon strips (horizon_strip.h) by circular cross-correlation: the
// second way skyloc recovers how far a robot is turned from a taught view, beside 1D
// SURF's RANSAC displacement (surf1d.h). It uses every column, not only blobs, so it
// needs no features and answers on a bland skyline; it assumes the two strips differ by a
// turn (a shift) and little else, which holds for a robot back on its taught route.
//
//   c(s) = sum_j (a_j - mean a) (b_(j+s mod n) - mean b) / (n std a std b)
//
// is the normalised (Pearson) correlation of the stored strip a with the test strip b
// shifted back by s columns, for every s = 0..n-1 (AlignStrips by the definition, O(n^2);
// StripCorrelator, below, by FFT for the frame path, with the same peak). The best s is
// refined to a fraction of a column by the parabola through c(s-1), c(s), c(s+1). The test strip's
// content is then turned by +s columns from the stored one: heading_offset_deg = s * 360 / n,
// wrapped to [-180, 180), the convention of LandmarkMatch::heading_offset_deg (a robot that turned
// by +psi about body z sees its scene turned by -psi). The peak's correlation is the confidence (1:
// identical up to the turn; near 0: unrelated), and the best correlation outside
// +-min_peak_separation columns of the peak says whether the turn is ambiguous (a periodic
// skyline).
//
// How much of c is chance: for two strips with the periodograms P_a, P_b but no relation,
// c(s) at any shift has the variance (Bartlett) (1/n) sum_k rho_a(k) rho_b(k), rho the
// strips' circular autocorrelations; by Parseval that is sum_f P_a P_b / (sum P_a sum P_b),
// which is exactly (1/n) sum_s c(s)^2 of the pair at hand. So the RMS of c over all shifts
// (`noise`) is the standard deviation a peak must stand above; smooth strips (few
// independent columns) have a large one, textured strips a small one. For related strips
// the peak's own share makes it an overestimate: a cautious one.
#pragma once

#include <complex>
#include <cstdint>
#include <span>
#include <unsupported/Eigen/FFT>
#include <vector>

namespace skyloc::dsp {

enum class StripAlignmentError : std::uint8_t {
  kOk,
  kSizeMismatch,  // the strips differ in length, or are shorter than 3 columns
  kFlat,          // a strip is constant: no turn can be read from it
  kNoStored,      // StripCorrelator::Align before Init and SetStored
};

// A sentence naming the problem and the fix.
const char* StripAlignmentErrorMessage(StripAlignmentError error);

struct StripAlignment {
  double shift_columns = 0.0;       // test content relative to stored, (-n/2, n/2]
  double heading_offset_deg = 0.0;  // the same in degrees, [-180, 180)
  float correlation = 0.0f;         // c at the best whole-column shift, -1..1
  float runner_up = 0.0f;           // best c further than min_peak_separation from it
  float second_peak = -1.0f;        // best local maximum of c as far away, -1 if none
  float noise = 0.0f;               // RMS of c over all shifts: chance's standard deviation
};

// The definition, O(n^2): every c(s) a dot product. For tools and as the reference of
// StripCorrelator, which the frame path uses.
// min_peak_separation: columns around the peak that belong to it (its width), >= 1.
// scratch: n doubles (or empty) to keep c(s) in, which halves the work; same result.
StripAlignmentError AlignStrips(std::span<const float> stored, std::span<const float> test,
                                StripAlignment* result, int min_peak_separation = 5,
                                std::span<double> scratch = {});

// The same alignment by FFT, O(n log n), for the frame path. With A and B the DFTs of the
// mean-removed strips, n std a std b c(s) is the inverse DFT of conj(A) B, and by Parseval
// sum_s c(s)^2 = sum_k |A_k|^2 |B_k|^2 / (n var a var b) (var: sums of squared
// deviations), so `noise` needs no second transform. The stored strip's spectrum is held
// (SetStored) while a localised robot matches the same route frame again, so such a frame
// costs one forward and one inverse transform. Any n >= 3 (Eigen's kissfft: mixed radix
// 2, 3, 4, 5 and a generic butterfly for larger primes).
//
// The answer is AlignStrips' to the last bit for the peak (shift_columns,
// heading_offset_deg, correlation): the transforms' c(s) agree with the dot products to
// ~1e-15 (double rounding times log n), so every shift within 1e-9 of the transforms'
// maximum, and the peak's two neighbours the parabola reads, are computed again as
// AlignStrips computes them; the first of equal maxima wins, as there. That also keeps
// the heading the same on every target whatever the twiddles' last bits (the libm's
// cos and sin). runner_up, second_peak and noise come from the transforms: within one
// float rounding of AlignStrips'.
class StripCorrelator {
 public:
  // Sizes the buffers and the transforms' plans for strips of `columns` (>= 3; false
  // otherwise). Allocates: not for the frame path.
  bool Init(int columns);

  // Holds `stored` (a copy) and its spectrum for the Align calls that follow. kFlat: held,
  // and every Align answers kFlat until another strip is set. Allocates nothing.
  StripAlignmentError SetStored(std::span<const float> stored);

  // Whether `stored` is, bit for bit, the strip held by SetStored.
  bool Holds(std::span<const float> stored) const;

  // Aligns `test` against the held stored strip, as AlignStrips(stored, test, ...).
  // Allocates nothing.
  StripAlignmentError Align(std::span<const float> test, StripAlignment* result,
                            int min_peak_separation = 5);

 private:
  using Complex = std::complex<double>;
  int columns_ = 0;
  bool has_stored_ = false;
  bool stored_flat_ = false;
  std::vector<float> stored_;
  double stored_mean_ = 0;
  double stored_var_ = 0;                 // sum of squared deviations
  std::vector<Complex> stored_spectrum_;  // n/2 + 1 bins of the mean-removed strip
  std::vector<Complex> spectrum_;         // the test strip's, then the cross spectrum
  std::vector<double> deviations_;        // the mean-removed test strip
  std::vector<double> correlation_;       // c(s), s = 0..n-1
  Eigen::FFT<double> fft_;
};

}  // namespace skyloc::dsp
