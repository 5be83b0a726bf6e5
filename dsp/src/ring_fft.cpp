#include "skyloc/dsp/ring_fft.h"

#include <Eigen/Core>
#include <cmath>
#include <numbers>

#include "skyloc/dsp/sh_grid.h"

namespace skyloc::dsp {
namespace {

using Lanes = Eigen::Array4f;
using LanesMap = Eigen::Map<Lanes>;
using ConstLanesMap = Eigen::Map<const Lanes>;

constexpr std::size_t kLanes = 4;
constexpr int kRingsPerBatch = 8;  // 4 lanes × 2 rings packed as re/im

}  // namespace

bool RingFft::Init(int rings, int n, std::span<const float> ring_scale) {
  rings_ = 0;
  if (rings < 1 || !IsPowerOfTwo(n) || n < 4 || n > kMaxShLongitudes ||
      (!ring_scale.empty() && ring_scale.size() != static_cast<std::size_t>(rings)))
    return false;
  const auto un = static_cast<std::size_t>(n);
  int log2n = 0;
  while ((1 << log2n) < n)
    ++log2n;
  bit_reverse_.assign(un, 0);
  for (int j = 0; j < n; ++j) {
    int r = 0;
    for (int b = 0; b < log2n; ++b)
      r |= ((j >> b) & 1) << (log2n - 1 - b);
    bit_reverse_[static_cast<std::size_t>(j)] = r;
  }
  twiddle_re_.assign(un / 2 * kLanes, 0.0f);
  twiddle_im_.assign(un / 2 * kLanes, 0.0f);
  for (std::size_t k = 0; k < un / 2; ++k) {
    const double angle = -2.0 * std::numbers::pi * static_cast<double>(k) / n;
    for (std::size_t q = 0; q < kLanes; ++q) {
      twiddle_re_[k * kLanes + q] = static_cast<float>(std::cos(angle));
      twiddle_im_[k * kLanes + q] = static_cast<float>(std::sin(angle));
    }
  }
  const int padded = (rings + kRingsPerBatch - 1) / kRingsPerBatch * kRingsPerBatch;
  scale_.assign(static_cast<std::size_t>(padded), 0.0f);
  for (std::size_t r = 0; r < static_cast<std::size_t>(rings); ++r)
    scale_[r] = ring_scale.empty() ? 1.0f : ring_scale[r];
  zeros_.assign(un, 0.0f);
  re_.assign(un * kLanes, 0.0f);
  im_.assign(un * kLanes, 0.0f);
  rings_ = rings;
  n_ = n;
  return true;
}

bool RingFft::Forward(std::span<const float> samples, std::span<float> cos_sums,
                      std::span<float> sin_sums) {
  const auto n = static_cast<std::size_t>(n_);
  const auto rings = static_cast<std::size_t>(rings_);
  if (rings_ == 0 || samples.size() != rings * n || cos_sums.size() != bins() * rings ||
      sin_sums.size() != bins() * rings)
    return false;
  float* re = re_.data();
  float* im = im_.data();
  for (std::size_t first = 0; first < rings; first += kRingsPerBatch) {
    // Load: lane q holds ring first+2q as the real part and first+2q+1 as the imaginary
    // part, in bit-reversed order for the in-place decimation in time. Missing rings read
    // zeros_. Four samples of four rings at a time: a 4×4 transpose turns rows (rings) into
    // lane vectors (samples).
    const float* ring_a[kLanes];
    const float* ring_b[kLanes];
    for (std::size_t q = 0; q < kLanes; ++q) {
      const std::size_t a = first + 2 * q;
      ring_a[q] = a < rings ? &samples[a * n] : zeros_.data();
      ring_b[q] = a + 1 < rings ? &samples[(a + 1) * n] : zeros_.data();
    }
    for (std::size_t j = 0; j < n; j += 4) {
      Eigen::Matrix4f block_a, block_b;
      for (std::size_t q = 0; q < kLanes; ++q) {
        const auto col = static_cast<Eigen::Index>(q);
        block_a.col(col) = Eigen::Map<const Eigen::Vector4f>(ring_a[q] + j);
        block_b.col(col) = Eigen::Map<const Eigen::Vector4f>(ring_b[q] + j);
      }
      block_a.transposeInPlace();
      block_b.transposeInPlace();
      for (std::size_t c = 0; c < 4; ++c) {
        const auto col = static_cast<Eigen::Index>(c);
        const std::size_t to = static_cast<std::size_t>(bit_reverse_[j + c]) * kLanes;
        Eigen::Map<Eigen::Vector4f>(re + to) = block_a.col(col);
        Eigen::Map<Eigen::Vector4f>(im + to) = block_b.col(col);
      }
    }
    // First stage (length 2): twiddle 1.
    for (std::size_t s = 0; s < n; s += 2) {
      LanesMap ar(re + s * kLanes), ai(im + s * kLanes);
      LanesMap br(re + (s + 1) * kLanes), bi(im + (s + 1) * kLanes);
      const Lanes tr = br, ti = bi;
      br = ar - tr;
      bi = ai - ti;
      ar += tr;
      ai += ti;
    }
    for (std::size_t half = 2; half < n; half *= 2) {
      const std::size_t twiddle_step = n / (2 * half);
      for (std::size_t s = 0; s < n; s += 2 * half) {
        for (std::size_t j = 0; j < half; ++j) {
          const ConstLanesMap wr(&twiddle_re_[j * twiddle_step * kLanes]);
          const ConstLanesMap wi(&twiddle_im_[j * twiddle_step * kLanes]);
          LanesMap ar(re + (s + j) * kLanes), ai(im + (s + j) * kLanes);
          LanesMap br(re + (s + j + half) * kLanes), bi(im + (s + j + half) * kLanes);
          const Lanes tr = br * wr - bi * wi;
          const Lanes ti = br * wi + bi * wr;
          br = ar - tr;
          bi = ai - ti;
          ar += tr;
          ai += ti;
        }
      }
    }
    // Unpack the two real rings of each lane from Z = FFT(a + i·b):
    //   A_k = (Z_k + conj Z_{n-k})/2,  B_k = (Z_k - conj Z_{n-k})/(2i),
    // and Σ x cos = Re X_k, Σ x sin = -Im X_k.
    for (std::size_t k = 0; k <= n / 2; ++k) {
      const std::size_t nk = (n - k) % n;
      const ConstLanesMap zr(re + k * kLanes), zi(im + k * kLanes);
      const ConstLanesMap yr(re + nk * kLanes), yi(im + nk * kLanes);
      const Lanes cos_a = 0.5f * (zr + yr);
      const Lanes sin_a = 0.5f * (yi - zi);
      const Lanes cos_b = 0.5f * (zi + yi);
      const Lanes sin_b = 0.5f * (zr - yr);
      for (std::size_t q = 0; q < kLanes; ++q) {
        const std::size_t out_ring = first + 2 * q;
        if (out_ring < rings) {
          cos_sums[k * rings + out_ring] = scale_[out_ring] * cos_a[static_cast<Eigen::Index>(q)];
          sin_sums[k * rings + out_ring] = scale_[out_ring] * sin_a[static_cast<Eigen::Index>(q)];
        }
        if (out_ring + 1 < rings) {
          cos_sums[k * rings + out_ring + 1] =
              scale_[out_ring + 1] * cos_b[static_cast<Eigen::Index>(q)];
          sin_sums[k * rings + out_ring + 1] =
              scale_[out_ring + 1] * sin_b[static_cast<Eigen::Index>(q)];
        }
      }
    }
  }
  return true;
}

}  // namespace skyloc::dsp
