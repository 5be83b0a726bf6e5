#include "skyloc/dsp/spherical_harmonics.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "skyloc/dsp/legendre.h"

namespace skyloc::dsp {
namespace {

constexpr double kSqrt2 = std::numbers::sqrt2;
// Table entries below this never matter: a ring contributes at most w·longitudes·|P̄| ≤
// 4π·1e-9 to a coefficient of a [0, 1] mask, far below float rounding of the result. They are
// stored as 0, and rings where a whole block of l is 0 are skipped.
constexpr float kNegligible = 1e-9f;

// Σ_i table(i, l_begin..l_begin+W-1) · (cos_i, sin_i): the Legendre sum of one block of l for
// one m. Eigen's fixed-size arrays vectorise with the baseline SIMD (SSE2 / NEON) and keep
// the 2·W/4 accumulators in registers; W = 16 gives enough independent additions to hide
// their latency.
template <int W>
void AccumulateBlock(const float* table, std::size_t stride, int rings, const float* weighted_cos,
                     const float* weighted_sin, float* out_cos, float* out_sin) {
  using Vec = Eigen::Array<float, W, 1>;
  Vec acc_cos = Vec::Zero();
  Vec acc_sin = Vec::Zero();
  for (int i = 0; i < rings; ++i) {
    const Eigen::Map<const Vec> t(table + static_cast<std::size_t>(i) * stride);
    acc_cos += t * weighted_cos[i];
    acc_sin += t * weighted_sin[i];
  }
  Eigen::Map<Vec> cos_out(out_cos);
  Eigen::Map<Vec> sin_out(out_sin);
  cos_out = acc_cos;
  sin_out = acc_sin;
}

std::size_t PaddedLength(int count) {
  return static_cast<std::size_t>((count + 7) / 8 * 8);
}

}  // namespace

namespace {

// y_lm(θ, φ) for all l < bands from the Legendre triangle of cos θ.
void ExpandRealSh(int bands, std::span<const double> legendre, double phi, std::span<double> out) {
  for (int m = 0; m < bands; ++m) {
    const double c = std::cos(m * phi);
    const double s = std::sin(m * phi);
    for (int l = m; l < bands; ++l) {
      const double p = legendre[LegendreIndex(l, m)];
      if (m == 0) {
        out[ShIndex(l, 0)] = p;
      } else {
        out[ShIndex(l, m)] = kSqrt2 * p * c;
        out[ShIndex(l, -m)] = kSqrt2 * p * s;
      }
    }
  }
}

}  // namespace

bool RealSphericalHarmonics(int bands, double cos_theta, double sin_theta, double phi,
                            std::span<double> legendre_scratch, std::span<double> out) {
  if (bands < 1 || out.size() < ShCoefficientCount(bands) ||
      !NormalisedLegendre(bands, cos_theta, sin_theta, legendre_scratch))
    return false;
  ExpandRealSh(bands, legendre_scratch, phi, out);
  return true;
}

// ---------------------------------------------------------------------------------------
// Fast projector

ShError ShProjector::Init(const ShGrid& grid, int bands) {
  bands_ = 0;
  if (!grid.initialised())
    return ShError::kNotInitialised;
  if (bands < 1 || bands > kMaxShBands)
    return ShError::kBandsOutOfRange;
  const int rings = grid.ring_count();
  const int longitudes = grid.longitudes();
  const auto ring_count = static_cast<std::size_t>(rings);

  // Legendre values of every ring in double, then laid out per m as rings × padded(L - m)
  // floats with √2 folded in for m > 0 (the staging table below).
  std::vector<double> legendre(ring_count * LegendreTriangleSize(bands));
  for (std::size_t i = 0; i < ring_count; ++i) {
    const ShRing& r = grid.rings()[i];
    NormalisedLegendre(bands, r.cos_theta, r.sin_theta,
                       std::span(legendre).subspan(i * LegendreTriangleSize(bands)));
  }
  std::size_t staging_size = 0;
  for (int m = 0; m < bands; ++m)
    staging_size += ring_count * PaddedLength(bands - m);
  std::vector<float> staging(staging_size, 0.0f);
  blocks_.clear();
  std::size_t m_offset = 0, table_size = 0;
  for (int m = 0; m < bands; ++m) {
    const std::size_t stride = PaddedLength(bands - m);
    const double scale = m == 0 ? 1.0 : kSqrt2;
    for (std::size_t i = 0; i < ring_count; ++i) {
      for (int l = m; l < bands; ++l) {
        // Negligible values become exact zeros: besides not mattering, tiny ones would be
        // float denormals, which cost x86 ~100 cycles per multiply.
        const double v = scale * legendre[i * LegendreTriangleSize(bands) + LegendreIndex(l, m)];
        staging[m_offset + i * stride + static_cast<std::size_t>(l - m)] =
            std::fabs(v) < static_cast<double>(kNegligible) ? 0.0f : static_cast<float>(v);
      }
    }
    for (int l_begin = m; l_begin < bands;) {
      MBlock b;
      b.m = m;
      b.l_begin = l_begin;
      b.width = bands - l_begin > 8 ? 16 : 8;
      const std::size_t column = static_cast<std::size_t>(l_begin - m);
      auto significant = [&](std::size_t i) {
        const float* row = &staging[m_offset + i * stride + column];
        for (int k = 0; k < b.width; ++k) {
          if (std::fabs(row[k]) >= kNegligible)
            return true;
        }
        return false;
      };
      std::size_t first = 0;
      while (first < ring_count && !significant(first))
        ++first;
      std::size_t end = ring_count;
      while (end > first && !significant(end - 1))
        --end;
      b.first_ring = static_cast<int>(first);
      b.end_ring = static_cast<int>(end);
      b.table_offset = m_offset + first * stride + column;  // in staging, until below
      b.stride = stride;
      blocks_.push_back(b);
      table_size += (end - first) * static_cast<std::size_t>(b.width);
      l_begin += b.width;
    }
    m_offset += ring_count * stride;
  }
  // The projection reads the whole table once a frame, block after block: each block's rows
  // (its significant rings × its width) stored one after the other, in the order Project
  // visits the blocks, make that one sequential stream with nothing skipped (the rings of
  // negligible values are left out), the cheapest read a cache and its prefetcher can
  // serve. The same values multiply the same sums in the same order: the same coefficients
  // to the bit.
  table_.assign(table_size, 0.0f);
  std::size_t next = 0;
  for (MBlock& b : blocks_) {
    const auto width = static_cast<std::size_t>(b.width);
    for (int i = b.first_ring; i < b.end_ring; ++i) {
      const float* row =
          &staging[b.table_offset + static_cast<std::size_t>(i - b.first_ring) * b.stride];
      std::copy(row, row + width, table_.begin() + static_cast<std::ptrdiff_t>(next));
      next += width;
    }
    b.table_offset = next - static_cast<std::size_t>(b.end_ring - b.first_ring) * width;
    b.stride = width;
  }

  // Which FFT bin holds Σ_j f·e^{-imφ_j}: m mod longitudes, folded into the half spectrum by
  // conjugation (which flips the sign of the sine sum).
  bin_.assign(static_cast<std::size_t>(bands), 0);
  bin_sign_.assign(static_cast<std::size_t>(bands), 1.0f);
  for (int m = 0; m < bands; ++m) {
    int k = m % longitudes;
    float sign = 1.0f;
    if (k > longitudes / 2) {
      k = longitudes - k;
      sign = -1.0f;
    }
    bin_[static_cast<std::size_t>(m)] = k;
    bin_sign_[static_cast<std::size_t>(m)] = sign;
  }
  std::vector<float> ring_weight(ring_count);
  for (std::size_t i = 0; i < ring_count; ++i)
    ring_weight[i] = static_cast<float>(grid.rings()[i].weight);
  if (!fft_.Init(rings, longitudes, ring_weight))
    return ShError::kLongitudesOutOfRange;
  cos_sums_.assign(fft_.bins() * ring_count, 0.0f);
  sin_sums_.assign(fft_.bins() * ring_count, 0.0f);

  rings_ = rings;
  longitudes_ = longitudes;
  bands_ = bands;
  return ShError::kOk;
}

ShError ShProjector::Project(std::span<const float> samples, std::span<float> coeffs) {
  if (bands_ == 0)
    return ShError::kNotInitialised;
  if (samples.size() != sample_count() || coeffs.size() != coefficient_count())
    return ShError::kSizeMismatch;
  fft_.Forward(samples, cos_sums_, sin_sums_);
  alignas(64) float block_cos[16];
  alignas(64) float block_sin[16];
  for (const MBlock& b : blocks_) {
    const auto m = static_cast<std::size_t>(b.m);
    const std::size_t bin_offset =
        static_cast<std::size_t>(bin_[m]) * static_cast<std::size_t>(rings_);
    const int ring_span = b.end_ring - b.first_ring;
    const float* wc = &cos_sums_[bin_offset + static_cast<std::size_t>(b.first_ring)];
    const float* ws = &sin_sums_[bin_offset + static_cast<std::size_t>(b.first_ring)];
    if (b.width == 16)
      AccumulateBlock<16>(table_.data() + b.table_offset, b.stride, ring_span, wc, ws, block_cos,
                          block_sin);
    else
      AccumulateBlock<8>(table_.data() + b.table_offset, b.stride, ring_span, wc, ws, block_cos,
                         block_sin);
    const int l_end = std::min(b.l_begin + b.width, bands_);
    const float sin_sign = bin_sign_[m];
    for (int l = b.l_begin; l < l_end; ++l) {
      const auto k = static_cast<std::size_t>(l - b.l_begin);
      coeffs[ShIndex(l, b.m)] = block_cos[k];
      if (b.m > 0)
        coeffs[ShIndex(l, -b.m)] = sin_sign * block_sin[k];
    }
  }
  return ShError::kOk;
}

// ---------------------------------------------------------------------------------------
// Naive reference

ShError ShNaiveProjector::Init(const ShGrid& grid, int bands) {
  bands_ = 0;
  if (!grid.initialised())
    return ShError::kNotInitialised;
  if (bands < 1 || bands > kMaxShBands)
    return ShError::kBandsOutOfRange;
  const std::size_t samples = grid.sample_count();
  const std::size_t coefficients = ShCoefficientCount(bands);
  if (coefficients > kMaxNaiveTableEntries / samples)
    return ShError::kTableTooLarge;
  table_.assign(coefficients * samples, 0.0f);
  sample_weight_.resize(samples);
  weighted_.assign(samples, 0.0);
  std::vector<double> legendre(LegendreTriangleSize(bands));
  std::vector<double> y(coefficients);
  const auto longitudes = static_cast<std::size_t>(grid.longitudes());
  for (std::size_t s = 0; s < samples; ++s) {
    const ShRing& r = grid.ring(static_cast<int>(s / longitudes));
    if (s % longitudes == 0)
      NormalisedLegendre(bands, r.cos_theta, r.sin_theta, legendre);
    ExpandRealSh(bands, legendre, grid.phi(static_cast<int>(s % longitudes)), y);
    for (std::size_t k = 0; k < coefficients; ++k)
      table_[k * samples + s] = static_cast<float>(y[k]);
    sample_weight_[s] = r.weight;
  }
  samples_ = samples;
  bands_ = bands;
  return ShError::kOk;
}

ShError ShNaiveProjector::Project(std::span<const float> samples, std::span<float> coeffs) {
  if (bands_ == 0)
    return ShError::kNotInitialised;
  if (samples.size() != samples_ || coeffs.size() != coefficient_count())
    return ShError::kSizeMismatch;
  for (std::size_t s = 0; s < samples_; ++s)
    weighted_[s] = sample_weight_[s] * static_cast<double>(samples[s]);
  for (std::size_t k = 0; k < coefficient_count(); ++k) {
    const float* row = &table_[k * samples_];
    double sum = 0.0;
    for (std::size_t s = 0; s < samples_; ++s)
      sum += static_cast<double>(row[s]) * weighted_[s];
    coeffs[k] = static_cast<float>(sum);
  }
  return ShError::kOk;
}

// ---------------------------------------------------------------------------------------
// Amplitudes and distances

ShError AmplitudeSpectrum(std::span<const float> coeffs, int bands, std::span<float> amplitudes,
                          AmplitudeNormalisation normalisation) {
  if (bands < 1 || bands > kMaxShBands)
    return ShError::kBandsOutOfRange;
  if (coeffs.size() != ShCoefficientCount(bands) ||
      amplitudes.size() != static_cast<std::size_t>(bands))
    return ShError::kSizeMismatch;
  // Band l is the contiguous run k = l²..l²+2l. A plain loop in double, in index order: a
  // vectorised float reduction (Eigen's sum()) adds in an order that depends on the SIMD
  // width and the buffer's alignment, so x86-64 (SSE) and armhf (no NEON) rounded the same
  // coefficients to amplitudes a bit apart. Squares of floats are exact in double, and
  // without fast-math the compiler keeps this order on every target.
  double total = 0.0;
  for (int l = 0; l < bands; ++l) {
    const std::size_t first = ShIndex(l, -l);
    double sum = 0.0;
    for (std::size_t k = first; k < first + static_cast<std::size_t>(2 * l + 1); ++k)
      sum += static_cast<double>(coeffs[k]) * static_cast<double>(coeffs[k]);
    total += sum;
    amplitudes[static_cast<std::size_t>(l)] = static_cast<float>(std::sqrt(sum));
  }
  double divisor = 1.0;
  if (normalisation == AmplitudeNormalisation::kDivideByA0)
    divisor = static_cast<double>(amplitudes[0]);
  else if (normalisation == AmplitudeNormalisation::kUnitL2)
    divisor = std::sqrt(total);
  if (normalisation != AmplitudeNormalisation::kNone) {
    const float inverse = divisor > 0.0 ? static_cast<float>(1.0 / divisor) : 0.0f;
    for (float& a : amplitudes)
      a *= inverse;
  }
  return ShError::kOk;
}

float DescriptorDistance(std::span<const float> a, std::span<const float> b,
                         DescriptorMetric metric) {
  if (a.size() != b.size())
    return std::numeric_limits<float>::quiet_NaN();
  double sum = 0.0;
  switch (metric) {
    case DescriptorMetric::kL1:
      for (std::size_t i = 0; i < a.size(); ++i)
        sum += std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
      return static_cast<float>(sum);
    case DescriptorMetric::kL2:
      for (std::size_t i = 0; i < a.size(); ++i) {
        const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
        sum += d * d;
      }
      return static_cast<float>(std::sqrt(sum));
    case DescriptorMetric::kCosine: {
      double aa = 0.0, bb = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i) {
        sum += static_cast<double>(a[i]) * static_cast<double>(b[i]);
        aa += static_cast<double>(a[i]) * static_cast<double>(a[i]);
        bb += static_cast<double>(b[i]) * static_cast<double>(b[i]);
      }
      if (aa == 0.0 && bb == 0.0)
        return 0.0f;
      if (aa == 0.0 || bb == 0.0)
        return 1.0f;
      return static_cast<float>(std::max(0.0, 1.0 - sum / std::sqrt(aa * bb)));
    }
  }
  return std::numeric_limits<float>::quiet_NaN();
}

}  // namespace skyloc::dsp
