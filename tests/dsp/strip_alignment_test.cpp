#include "skyloc/dsp/strip_alignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

// A smooth skyline-like strip from a few harmonics, evaluated at column j - shift: the
// same content turned by +shift columns (shift may be fractional: the analytic answer).
std::vector<float> Harmonics(int n, double shift, unsigned seed, double noise_sd = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2 * kPi);
  std::uniform_real_distribution<double> amplitude(5.0, 30.0);
  double a[6], p[6];
  for (int k = 0; k < 6; ++k) {
    a[k] = amplitude(rng) / (k + 1);
    p[k] = phase(rng);
  }
  std::mt19937 noise_rng(seed + 1000);
  std::normal_distribution<double> noise(0.0, noise_sd > 0 ? noise_sd : 1.0);
  std::vector<float> s(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    double v = 100;
    for (int k = 0; k < 6; ++k)
      v += a[k] * std::sin(2 * kPi * (k + 1) * (j - shift) / n + p[k]);
    if (noise_sd > 0)
      v += noise(noise_rng);
    s[static_cast<std::size_t>(j)] = static_cast<float>(v);
  }
  return s;
}

TEST(StripAlignmentTest, RecoversWholeAndFractionalTurnsOfASmoothStrip) {
  const int n = 360;
  const std::vector<float> stored = Harmonics(n, 0.0, 7);
  for (const double shift : {0.0, 12.0, -40.0, 7.3, -101.6, 179.0, -179.5}) {
    StripAlignment r;
    ASSERT_EQ(AlignStrips(stored, Harmonics(n, shift, 7), &r), StripAlignmentError::kOk);
    // The parabola through three samples of a smooth peak: within 0.1 column.
    EXPECT_NEAR(r.shift_columns, shift, 0.1) << "shift " << shift;
    double degrees = shift * 360.0 / n;
    double error = r.heading_offset_deg - degrees;
    error -= 360.0 * std::round(error / 360.0);
    EXPECT_LE(std::abs(error), 0.1) << "shift " << shift;
    EXPECT_GT(r.correlation, 0.999f);
  }
}

TEST(StripAlignmentTest, NoiseLowersTheCorrelationNotTheTurn) {
  const int n = 360;
  const std::vector<float> stored = Harmonics(n, 0.0, 3);
  StripAlignment r;
  ASSERT_EQ(AlignStrips(stored, Harmonics(n, 55.0, 3, 8.0), &r), StripAlignmentError::kOk);
  EXPECT_NEAR(r.shift_columns, 55.0, 0.5);
  EXPECT_LT(r.correlation, 0.99f);
  EXPECT_GT(r.correlation, 0.5f);
  EXPECT_LT(r.runner_up, r.correlation);
}

TEST(StripAlignmentTest, UnrelatedStripsCorrelateWeakly) {
  const int n = 360;
  StripAlignment related, unrelated;
  ASSERT_EQ(AlignStrips(Harmonics(n, 0.0, 1), Harmonics(n, 30.0, 1, 4.0), &related),
            StripAlignmentError::kOk);
  ASSERT_EQ(AlignStrips(Harmonics(n, 0.0, 1), Harmonics(n, 30.0, 2, 4.0), &unrelated),
            StripAlignmentError::kOk);
  EXPECT_GT(related.correlation, unrelated.correlation + 0.1f);
}

TEST(StripAlignmentTest, APeriodicSkylineIsAmbiguous) {
  // Four identical buildings: the turn is known only modulo 90 degrees, and the runner-up
  // peak says so by equalling the best.
  const int n = 360;
  std::vector<float> stored(n), test(n);
  for (int j = 0; j < n; ++j) {
    stored[static_cast<std::size_t>(j)] = static_cast<float>(std::sin(2 * kPi * 4 * j / n));
    test[static_cast<std::size_t>(j)] = static_cast<float>(std::sin(2 * kPi * 4 * (j - 10) / n));
  }
  StripAlignment r;
  ASSERT_EQ(AlignStrips(stored, test, &r), StripAlignmentError::kOk);
  EXPECT_NEAR(std::fmod(r.shift_columns + 900.0, 90.0), 10.0, 0.1);
  EXPECT_NEAR(r.runner_up, r.correlation, 1e-4f);
}

TEST(StripAlignmentTest, RefusesFlatAndMismatchedStrips) {
  StripAlignment r;
  const std::vector<float> flat(360, 5.0f);
  const std::vector<float> smooth = Harmonics(360, 0.0, 1);
  EXPECT_EQ(AlignStrips(flat, smooth, &r), StripAlignmentError::kFlat);
  EXPECT_EQ(AlignStrips(smooth, flat, &r), StripAlignmentError::kFlat);
  EXPECT_EQ(AlignStrips(smooth, Harmonics(180, 0.0, 1), &r), StripAlignmentError::kSizeMismatch);
  EXPECT_EQ(AlignStrips(std::vector<float>{1, 2}, std::vector<float>{1, 2}, &r),
            StripAlignmentError::kSizeMismatch);
  EXPECT_NE(std::string(StripAlignmentErrorMessage(StripAlignmentError::kFlat)).find("constant"),
            std::string::npos);
}

// noise is chance's standard deviation of c: Bartlett's variance of the cross-correlation
// of two unrelated series, (1/n) sum_k rho_a(k) rho_b(k), computed here from the strips'
// own circular autocorrelations (not from c).
TEST(StripAlignmentTest, NoiseIsBartlettsStandardDeviation) {
  const int n = 360;
  for (const unsigned seed : {1u, 4u}) {
    const std::vector<float> a = Harmonics(n, 0.0, seed, 6.0);
    const std::vector<float> b = Harmonics(n, 40.0, seed + 1, 3.0);
    auto autocorrelation = [n](const std::vector<float>& x) {
      double mean = 0;
      for (float v : x)
        mean += static_cast<double>(v);
      mean /= n;
      std::vector<double> rho(static_cast<std::size_t>(n));
      for (int k = 0; k < n; ++k) {
        double sum = 0;
        for (int j = 0; j < n; ++j)
          sum += (static_cast<double>(x[static_cast<std::size_t>(j)]) - mean) *
                 (static_cast<double>(x[static_cast<std::size_t>((j + k) % n)]) - mean);
        rho[static_cast<std::size_t>(k)] = sum;
      }
      const double zero = rho[0];
      for (double& r : rho)
        r /= zero;
      return rho;
    };
    const std::vector<double> rho_a = autocorrelation(a), rho_b = autocorrelation(b);
    double variance = 0;
    for (int k = 0; k < n; ++k)
      variance += rho_a[static_cast<std::size_t>(k)] * rho_b[static_cast<std::size_t>(k)];
    variance /= n;
    StripAlignment r;
    ASSERT_EQ(AlignStrips(a, b, &r), StripAlignmentError::kOk);
    EXPECT_NEAR(r.noise, std::sqrt(variance), 1e-4 * std::sqrt(variance)) << seed;
  }
}

// Scratch only saves the second pass: the same result to the bit.
TEST(StripAlignmentTest, ScratchGivesTheSameResult) {
  const int n = 360;
  std::vector<double> scratch(n);
  for (const unsigned seed : {2u, 5u, 8u}) {
    const std::vector<float> a = Harmonics(n, 0.0, seed, 5.0);
    const std::vector<float> b = Harmonics(n, 33.3, seed, 5.0);
    StripAlignment plain, kept;
    ASSERT_EQ(AlignStrips(a, b, &plain), StripAlignmentError::kOk);
    ASSERT_EQ(AlignStrips(a, b, &kept, 5, scratch), StripAlignmentError::kOk);
    EXPECT_EQ(plain.shift_columns, kept.shift_columns);
    EXPECT_EQ(plain.correlation, kept.correlation);
    EXPECT_EQ(plain.runner_up, kept.runner_up);
    EXPECT_EQ(plain.second_peak, kept.second_peak);
    EXPECT_EQ(plain.noise, kept.noise);
    EXPECT_LE(plain.second_peak, plain.runner_up);
  }
}

TEST(StripAlignmentTest, AllocatesNothing) {
  const std::vector<float> a = Harmonics(360, 0.0, 9);
  const std::vector<float> b = Harmonics(360, 20.0, 9);
  StripAlignment r;
  {
    AllocationScope scope;
    ASSERT_EQ(AlignStrips(a, b, &r), StripAlignmentError::kOk);
    EXPECT_EQ(scope.allocations(), 0u);
  }
  // The transforms' other paths too: a length not a multiple of 4 (a complex transform of
  // the whole strip) and a prime one (the generic butterfly).
  for (const int n : {360, 150, 149}) {
    const std::vector<float> c = Harmonics(n, 0.0, 9), d = Harmonics(n, 20.0, 9);
    StripCorrelator correlator;
    ASSERT_TRUE(correlator.Init(n));
    AllocationScope scope;
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(correlator.SetStored(i % 2 == 0 ? c : d), StripAlignmentError::kOk);
      ASSERT_EQ(correlator.Align(i % 2 == 0 ? d : c, &r), StripAlignmentError::kOk);
    }
    EXPECT_EQ(scope.allocations(), 0u) << n;
  }
}

// Strips as the route stores them: bytes, columns of random width and level (a skyline's
// blocks) plus noise, so the correlation has many near-equal shifts.
std::vector<float> ByteStrip(int n, std::mt19937* rng) {
  std::uniform_int_distribution<int> level(0, 255), width(1, 12), noise(-6, 6);
  std::vector<float> s(static_cast<std::size_t>(n));
  int j = 0;
  while (j < n) {
    const int w = width(*rng), v = level(*rng);
    for (int i = 0; i < w && j < n; ++i, ++j)
      s[static_cast<std::size_t>(j)] = static_cast<float>(std::clamp(v + noise(*rng), 0, 255));
  }
  return s;
}

// The correlator by FFT against the definition (AlignStrips), on turned and noisy copies
// and on unrelated strips, at every length the heading allows and some it does not
// (odd, prime, tiny). The peak is computed again by the definition, so the shift, the
// degrees and the peak's correlation must be the same to the bit. runner_up, second_peak
// and noise come from the transforms, whose c(s) differ from the dot products' by
// rounding: each of ~n log2 n double operations of relative error 2^-53 on terms of size
// <= 1, so |dc| < n log2 n 2^-53 < 1e-12 for n <= 1000; rounded to float (2^-24 ~ 6e-8 at
// 1), the two then differ by at most one float step: the test allows exactly that.
TEST(StripAlignmentTest, CorrelatorByFftIsTheDefinition) {
  std::mt19937 rng(33);
  std::uniform_int_distribution<int> any_shift(0, 1000);
  std::uniform_int_distribution<int> change(-20, 20);
  const auto one_step = [](float a, float b) { return a == b || std::nextafter(a, b) == b; };
  int compared = 0;
  for (const int n : {360, 180, 148, 149, 150, 361, 7, 3}) {
    StripCorrelator correlator;
    ASSERT_TRUE(correlator.Init(n)) << n;
    for (int pair = 0; pair < 40; ++pair) {
      const std::vector<float> stored = ByteStrip(n, &rng);
      std::vector<float> test(stored.size());
      const int shift = any_shift(rng) % n;
      const bool unrelated = pair % 4 == 3;
      const std::vector<float> other = ByteStrip(n, &rng);
      for (int j = 0; j < n; ++j) {
        const float v = unrelated ? other[static_cast<std::size_t>(j)]
                                  : stored[static_cast<std::size_t>(((j - shift) % n + n) % n)];
        test[static_cast<std::size_t>(j)] =
            static_cast<float>(std::clamp(static_cast<int>(v) + change(rng) * (pair % 3), 0, 255));
      }
      StripAlignment reference, by_fft;
      const StripAlignmentError expected = AlignStrips(stored, test, &reference);
      if (!correlator.Holds(stored))
        (void)correlator.SetStored(stored);
      ASSERT_EQ(correlator.Align(test, &by_fft), expected) << n << " " << pair;
      if (expected != StripAlignmentError::kOk)
        continue;
      ++compared;
      EXPECT_EQ(by_fft.shift_columns, reference.shift_columns) << n << " " << pair;
      EXPECT_EQ(by_fft.heading_offset_deg, reference.heading_offset_deg) << n << " " << pair;
      EXPECT_EQ(by_fft.correlation, reference.correlation) << n << " " << pair;
      EXPECT_TRUE(one_step(by_fft.runner_up, reference.runner_up))
          << n << " " << pair << ": " << by_fft.runner_up << " " << reference.runner_up;
      EXPECT_TRUE(one_step(by_fft.second_peak, reference.second_peak))
          << n << " " << pair << ": " << by_fft.second_peak << " " << reference.second_peak;
      EXPECT_TRUE(one_step(by_fft.noise, reference.noise))
          << n << " " << pair << ": " << by_fft.noise << " " << reference.noise;
    }
  }
  EXPECT_GT(compared, 300);
}

// Equal maxima (a periodic skyline turned by whole periods) go to the first shift, as the
// definition gives them; the smooth harmonics strips agree too.
TEST(StripAlignmentTest, CorrelatorTakesTheFirstOfEqualPeaks) {
  const int n = 360;
  std::mt19937 rng(4);
  const std::vector<float> building = ByteStrip(90, &rng);
  std::vector<float> periodic(n);
  for (int j = 0; j < n; ++j)
    periodic[static_cast<std::size_t>(j)] = building[static_cast<std::size_t>(j % 90)];
  StripCorrelator correlator;
  ASSERT_TRUE(correlator.Init(n));
  ASSERT_EQ(correlator.SetStored(periodic), StripAlignmentError::kOk);
  StripAlignment reference, by_fft;
  ASSERT_EQ(AlignStrips(periodic, periodic, &reference), StripAlignmentError::kOk);
  ASSERT_EQ(correlator.Align(periodic, &by_fft), StripAlignmentError::kOk);
  EXPECT_EQ(reference.shift_columns, 0.0);
  EXPECT_EQ(by_fft.shift_columns, reference.shift_columns);
  EXPECT_EQ(by_fft.correlation, reference.correlation);
  EXPECT_EQ(by_fft.second_peak, reference.second_peak);  // the next period: exactly 1 too
  for (const unsigned seed : {2u, 5u, 8u}) {
    const std::vector<float> a = Harmonics(n, 0.0, seed, 5.0);
    const std::vector<float> b = Harmonics(n, 33.3, seed, 5.0);
    ASSERT_EQ(AlignStrips(a, b, &reference), StripAlignmentError::kOk);
    ASSERT_EQ(correlator.SetStored(a), StripAlignmentError::kOk);
    ASSERT_EQ(correlator.Align(b, &by_fft), StripAlignmentError::kOk);
    EXPECT_EQ(by_fft.shift_columns, reference.shift_columns) << seed;
    EXPECT_EQ(by_fft.correlation, reference.correlation) << seed;
  }
}

TEST(StripAlignmentTest, CorrelatorRefusesWhatTheDefinitionRefuses) {
  StripCorrelator correlator;
  StripAlignment r;
  const std::vector<float> smooth = Harmonics(360, 0.0, 1), flat(360, 4.0f);
  EXPECT_EQ(correlator.Align(smooth, &r), StripAlignmentError::kNoStored);
  EXPECT_EQ(correlator.SetStored(smooth), StripAlignmentError::kNoStored);
  EXPECT_FALSE(correlator.Init(2));
  ASSERT_TRUE(correlator.Init(360));
  EXPECT_EQ(correlator.Align(smooth, &r), StripAlignmentError::kNoStored);
  EXPECT_EQ(correlator.SetStored(Harmonics(180, 0.0, 1)), StripAlignmentError::kSizeMismatch);
  EXPECT_EQ(correlator.SetStored(flat), StripAlignmentError::kFlat);
  EXPECT_TRUE(correlator.Holds(flat));
  EXPECT_EQ(correlator.Align(smooth, &r), StripAlignmentError::kFlat);
  ASSERT_EQ(correlator.SetStored(smooth), StripAlignmentError::kOk);
  EXPECT_FALSE(correlator.Holds(flat));
  EXPECT_EQ(correlator.Align(flat, &r), StripAlignmentError::kFlat);
  EXPECT_EQ(correlator.Align(Harmonics(180, 0.0, 1), &r), StripAlignmentError::kSizeMismatch);
  EXPECT_NE(
      std::string(StripAlignmentErrorMessage(StripAlignmentError::kNoStored)).find("SetStored"),
      std::string::npos);
}

}  // namespace
}  // namespace skyloc::dsp
