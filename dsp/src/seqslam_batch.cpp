#include "skyloc/dsp/seqslam_batch.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "float4.h"
#include "index_size.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace skyloc::dsp {
namespace {

// Bytes of reference rows one tile holds: every query of the call passes over the tile,
// so it should stay in L1 (32 KiB on the machines this runs on) next to the queries of
// one kernel. Measured at 3576 x 3576 bytes: 256 KiB tiles (L2) waited on loads and took
// twice as long.
constexpr std::size_t kTileBytes = 16 * 1024;

// ---- Float rows: DifferenceColumn's arithmetic, two references x two queries --------------

using simd::Abs4;
using simd::Float4;
using simd::Load4;

// The mean absolute difference from the eight partial sums of one pair, exactly as
// DifferenceRows in seqslam.cpp finishes a row: the tail elements go into lanes 0.., the
// lanes are added ((0+1)+(2+3))+((4+5)+(6+7)), then scaled by 1/dim.
float FinishFloat(Float4 lo, Float4 hi, const float* row, const float* q, std::size_t whole,
                  std::size_t d, float inv_dim) {
  float lane[8];
  std::memcpy(lane, &lo, sizeof lo);
  std::memcpy(lane + 4, &hi, sizeof hi);
  for (std::size_t i = whole; i < d; ++i)
    lane[i - whole] += std::fabs(row[i] - q[i]);
  const float sum =
      ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
  return sum * inv_dim;
}

// NR references x NQ queries. Each pair keeps its own two registers of partial sums and
// adds |ref - query| for elements 0, 8, 16, ... in that order, as DifferenceRows does; the
// low and high halves are done one after the other so the 2 x 2 case fits in 16 registers.
template <std::size_t NR, std::size_t NQ>
void FloatKernel(const float* const* refs, const float* const* qs, std::size_t d, float inv_dim,
                 float* out, std::size_t stride) {
  const std::size_t whole = d - d % 8;
  Float4 lo[NR * NQ] = {}, hi[NR * NQ] = {};
  for (std::size_t i = 0; i < whole; i += 8) {
    Float4 r[NR], q[NQ];
    for (std::size_t a = 0; a < NR; ++a)
      r[a] = Load4(refs[a] + i);
    for (std::size_t b = 0; b < NQ; ++b)
      q[b] = Load4(qs[b] + i);
    for (std::size_t b = 0; b < NQ; ++b)
      for (std::size_t a = 0; a < NR; ++a)
        lo[b * NR + a] += Abs4(r[a] - q[b]);
    for (std::size_t a = 0; a < NR; ++a)
      r[a] = Load4(refs[a] + i + 4);
    for (std::size_t b = 0; b < NQ; ++b)
      q[b] = Load4(qs[b] + i + 4);
    for (std::size_t b = 0; b < NQ; ++b)
      for (std::size_t a = 0; a < NR; ++a)
        hi[b * NR + a] += Abs4(r[a] - q[b]);
  }
  for (std::size_t b = 0; b < NQ; ++b) {
    for (std::size_t a = 0; a < NR; ++a) {
      out[b * stride + a] =
          FinishFloat(lo[b * NR + a], hi[b * NR + a], refs[a], qs[b], whole, d, inv_dim);
    }
  }
}

// ---- Byte rows: integer sums of absolute differences -------------------------------------

// Sum over the pair of |ref - query| as an exact integer (at most 255 x dim).
template <std::size_t NR, std::size_t NQ>
void ByteKernel(const std::uint8_t* const* refs, const std::uint8_t* const* qs, std::size_t d,
                float inv, float* out, std::size_t stride) {
  std::uint32_t sum[NR * NQ] = {};
  std::size_t i = 0;
#if defined(__SSE2__)
  // psadbw: |a - b| of 16 bytes summed into two 64-bit halves.
  __m128i acc[NR * NQ];
  for (__m128i& x : acc)
    x = _mm_setzero_si128();
  for (; i + 16 <= d; i += 16) {
    __m128i r[NR], q[NQ];
    for (std::size_t a = 0; a < NR; ++a)
      r[a] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(refs[a] + i));
    for (std::size_t b = 0; b < NQ; ++b)
      q[b] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(qs[b] + i));
    for (std::size_t b = 0; b < NQ; ++b)
      for (std::size_t a = 0; a < NR; ++a)
        acc[b * NR + a] = _mm_add_epi64(acc[b * NR + a], _mm_sad_epu8(r[a], q[b]));
  }
  for (std::size_t p = 0; p < NR * NQ; ++p) {
    sum[p] = static_cast<std::uint32_t>(_mm_cvtsi128_si32(acc[p])) +
             static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(acc[p], 8)));
  }
#elif defined(__aarch64__) && defined(__ARM_NEON)
  // uabal: |a - b| of 8 bytes widened and added into 16-bit lanes (at most 2 x 255 a lane
  // per 16 bytes), folded into 32-bit lanes every 64 steps, long before they could wrap.
  uint32x4_t acc32[NR * NQ];
  for (uint32x4_t& x : acc32)
    x = vdupq_n_u32(0);
  while (i + 16 <= d) {
    uint16x8_t acc16[NR * NQ];
    for (uint16x8_t& x : acc16)
      x = vdupq_n_u16(0);
    for (int step = 0; step < 64 && i + 16 <= d; ++step, i += 16) {
      uint8x16_t r[NR], q[NQ];
      for (std::size_t a = 0; a < NR; ++a)
        r[a] = vld1q_u8(refs[a] + i);
      for (std::size_t b = 0; b < NQ; ++b)
        q[b] = vld1q_u8(qs[b] + i);
      for (std::size_t b = 0; b < NQ; ++b) {
        for (std::size_t a = 0; a < NR; ++a) {
          uint16x8_t& x = acc16[b * NR + a];
          x = vabal_u8(x, vget_low_u8(r[a]), vget_low_u8(q[b]));
          x = vabal_high_u8(x, r[a], q[b]);
        }
      }
    }
    for (std::size_t p = 0; p < NR * NQ; ++p)
      acc32[p] = vpadalq_u16(acc32[p], acc16[p]);
  }
  for (std::size_t p = 0; p < NR * NQ; ++p)
    sum[p] = vaddvq_u32(acc32[p]);
#endif
  for (std::size_t b = 0; b < NQ; ++b) {
    for (std::size_t a = 0; a < NR; ++a) {
      std::uint32_t s = sum[b * NR + a];
      for (std::size_t k = i; k < d; ++k) {
        const int diff = static_cast<int>(refs[a][k]) - static_cast<int>(qs[b][k]);
        s += static_cast<std::uint32_t>(diff < 0 ? -diff : diff);
      }
      // s < 2^24 for any dim below 65 793: the float is exact, and so is the product when
      // dim is a power of two (the vanilla descriptor's 2048).
      out[b * stride + a] = static_cast<float>(s) * inv;
    }
  }
}

// The tile loop shared by both element types: references in tiles of kTileBytes (they
// stay in L1 while every query of [q0, q1) passes over them, so the references are read
// from memory once per call), two references x up to QB queries per kernel call; the ends
// take narrower kernels, which do the same per-pair arithmetic.
template <std::size_t QB, typename T, typename Kernel>
void Tile(const T* ref, const T* query, std::size_t d, int r0, int r1, int q0, int q1, float* out,
          std::size_t stride, Kernel kernel) {
  const int tile = std::max(2, static_cast<int>(kTileBytes / (d * sizeof(T))) & ~1);
  constexpr int kQ = static_cast<int>(QB);
  for (int t0 = r0; t0 < r1; t0 += tile) {
    const int t1 = std::min(r1, t0 + tile);
    for (int q = q0; q < q1; q += kQ) {
      const int nq = std::min(kQ, q1 - q);
      const T* qs[QB];
      for (int b = 0; b < kQ; ++b)
        qs[b] = query + Sz(q + std::min(b, nq - 1)) * d;
      float* o = out + Sz(q - q0) * stride;
      const auto call = [&]<std::size_t NR>(const T* const* rs, float* at) {
        if constexpr (QB >= 4) {
          if (nq == 4) {
            kernel.template operator()<NR, 4>(rs, qs, at, stride);
            return;
          }
          if (nq == 3) {
            kernel.template operator()<NR, 3>(rs, qs, at, stride);
            return;
          }
        }
        if (nq == 2) {
          kernel.template operator()<NR, 2>(rs, qs, at, stride);
        } else {
          kernel.template operator()<NR, 1>(rs, qs, at, stride);
        }
      };
      int r = t0;
      for (; r + 2 <= t1; r += 2) {
        const T* rs[2] = {ref + Sz(r) * d, ref + Sz(r + 1) * d};
        call.template operator()<2>(rs, o + (r - r0));
      }
      if (r < t1) {
        const T* rs[1] = {ref + Sz(r) * d};
        call.template operator()<1>(rs, o + (r - r0));
      }
    }
  }
}

}  // namespace

void QuantiseToBytes(std::span<const float> values, std::span<std::uint8_t> out) {
  for (std::size_t i = 0; i < values.size() && i < out.size(); ++i) {
    // x * 16 is exact and floor(y + 0.5) rounds halves up the same on every machine.
    float v = std::floor(values[i] * kByteDescriptorScale + 0.5f) + 128.0f;
    if (!(v == v))
      v = 128.0f;  // NaN: no difference information
    out[i] = static_cast<std::uint8_t>(std::clamp(v, 0.0f, 255.0f));
  }
}

void DifferenceTile(const DescriptorRows& reference, const DescriptorRows& query, int r0, int r1,
                    int q0, int q1, float* out, std::size_t out_stride) {
  const std::size_t d = Sz(reference.dim);
  if (reference.is_bytes()) {
    const float inv = 1.0f / (kByteDescriptorScale * static_cast<float>(reference.dim));
    Tile<4>(reference.bytes.data(), query.bytes.data(), d, r0, r1, q0, q1, out, out_stride,
            [&]<std::size_t NR, std::size_t NQ>(
                const std::uint8_t* const* rs, const std::uint8_t* const* qs, float* o,
                std::size_t stride) { ByteKernel<NR, NQ>(rs, qs, d, inv, o, stride); });
  } else {
    const float inv_dim = 1.0f / static_cast<float>(reference.dim);
    Tile<2>(reference.floats.data(), query.floats.data(), d, r0, r1, q0, q1, out, out_stride,
            [&]<std::size_t NR, std::size_t NQ>(const float* const* rs, const float* const* qs,
                                                float* o, std::size_t stride) {
              FloatKernel<NR, NQ>(rs, qs, d, inv_dim, o, stride);
            });
  }
}

// ---- BlockedSeqSlam ----------------------------------------------------------------------

SeqSlamError BlockedSeqSlam::Init(const DescriptorRows& reference, const DescriptorRows& query,
                                  const SeqSlamParams& params, SeqSlamWindow window,
                                  const BlockedSeqSlamOptions& options,
                                  std::span<SeqSlamMatch> matches) {
  SeqSlamError e = search_.Init(params);
  if (e != SeqSlamError::kOk)
    return e;
  if (reference.dim < 1 || query.dim != reference.dim)
    return SeqSlamError::kBadDimension;
  const std::size_t d = Sz(reference.dim);
  if (reference.is_bytes() != query.is_bytes())
    return SeqSlamError::kSizeMismatch;
  const std::size_t ref_size =
      reference.is_bytes() ? reference.bytes.size() : reference.floats.size();
  const std::size_t query_size = query.is_bytes() ? query.bytes.size() : query.floats.size();
  if (ref_size % d != 0 || query_size % d != 0 || options.block_columns < 1)
    return SeqSlamError::kSizeMismatch;
  reference_ = reference;
  query_ = query;
  params_ = params;
  window_ = window;
  n_ref_ = reference.count();
  n_query_ = query.count();
  if (matches.size() != Sz(n_query_))
    return SeqSlamError::kSizeMismatch;
  matches_ = matches;
  block_ = std::min(options.block_columns, std::max(1, n_query_));  // no overflow below
  block_count_ = (n_query_ + block_ - 1) / block_;
  slots_ = std::min(n_query_, block_ + params.sequence_length - 1);
  store_.assign(n_ref_ > 0 ? Sz(slots_) * Sz(n_ref_) : 0, 0.0f);
  have_begin_ = have_end_ = 0;
  t_begin_ = t_end_ = new_begin_ = new_end_ = 0;
  return SeqSlamError::kOk;
}

void BlockedSeqSlam::WindowOf(int t, int* first, int* last) const {
  const int len = params_.sequence_length;
  // Centred: frames t - ds/2 .. t - ds/2 + ds - 1 (note 1 in seqslam.h). Trailing:
  // t - ds + 1 .. t. As SeqSlamFromDifferences.
  *first = window_ == SeqSlamWindow::kCentred ? t - len / 2 : t - len + 1;
  *last = *first + len;
  if (*first < 0 || *last > n_query_ || n_ref_ == 0)
    *last = *first;  // no full window: no columns, no match
}

void BlockedSeqSlam::Begin(int block) {
  t_begin_ = std::min(n_query_, block * block_);
  t_end_ = std::min(n_query_, t_begin_ + block_);
  // The columns the block's windows read: contiguous, at most block + ds - 1 of them.
  int need_begin = n_query_, need_end = 0;
  for (int t = t_begin_; t < t_end_; ++t) {
    int first = 0, last = 0;
    WindowOf(t, &first, &last);
    if (first < last) {
      need_begin = std::min(need_begin, first);
      need_end = std::max(need_end, last);
    }
  }
  if (need_begin >= need_end) {
    new_begin_ = new_end_ = 0;
    return;
  }
  // Blocks come in order, so the columns kept from the last block are a prefix of these.
  if (have_end_ > need_begin && have_begin_ <= need_begin) {
    new_begin_ = have_end_;
  } else {
    new_begin_ = need_begin;
  }
  new_end_ = std::max(new_begin_, need_end);
  have_begin_ = need_begin;
  have_end_ = need_end;
}

float* BlockedSeqSlam::Column(int q) {
  return store_.data() + Sz(q % slots_) * Sz(n_ref_);
}

std::size_t BlockedSeqSlam::ScratchFloats() const {
  return Sz(n_ref_) * Sz(kColumnGroup);
}

void BlockedSeqSlam::ComputeColumns(int begin, int end, std::span<float> scratch) {
  for (int q0 = new_begin_ + begin; q0 < new_begin_ + end; q0 += kColumnGroup) {
    const int q1 = std::min(new_begin_ + end, q0 + kColumnGroup);
    DifferenceTile(reference_, query_, 0, n_ref_, q0, q1, scratch.data(), Sz(n_ref_));
    for (int q = q0; q < q1; ++q) {
      EnhanceColumn(scratch.subspan(Sz(q - q0) * Sz(n_ref_), Sz(n_ref_)), params_.contrast_window,
                    std::span<float>(Column(q), Sz(n_ref_)));
    }
  }
}

void BlockedSeqSlam::Search(int begin, int end, std::span<float> scores) {
  const int len = params_.sequence_length;
  const float* columns[kMaxSequenceLength];
  for (int t = t_begin_ + begin; t < t_begin_ + end; ++t) {
    SeqSlamMatch& match = matches_[Sz(t)];
    match = SeqSlamMatch{};
    int first = 0, last = 0;
    WindowOf(t, &first, &last);
    if (first >= last)
      continue;
    for (int j = 0; j < len; ++j)
      columns[j] = Column(first + j);
    match =
        search_.Search(std::span<const float* const>(columns, Sz(len)), n_ref_, t - first, scores);
  }
}

void BlockedSeqSlam::Run() {
  std::vector<float> scratch(ScratchFloats());
  std::vector<float> scores(ScoreFloats());
  for (int b = 0; b < block_count_; ++b) {
    Begin(b);
    ComputeColumns(0, ColumnCount(), scratch);
    Search(0, SearchCount(), scores);
  }
}

SeqSlamError BlockedBatchSeqSlam(const DescriptorRows& reference, const DescriptorRows& query,
                                 const SeqSlamParams& params, SeqSlamWindow window,
                                 const BlockedSeqSlamOptions& options,
                                 std::span<SeqSlamMatch> matches) {
  BlockedSeqSlam engine;
  const SeqSlamError e = engine.Init(reference, query, params, window, options, matches);
  if (e != SeqSlamError::kOk)
    return e;
  engine.Run();
  return SeqSlamError::kOk;
}

}  // namespace skyloc::dsp
