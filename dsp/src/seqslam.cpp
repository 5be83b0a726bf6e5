#include "skyloc/dsp/seqslam.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <type_traits>

#include "float4.h"
#include "index_size.h"

namespace skyloc::dsp {
namespace {

// Number of velocities vmin, vmin + vstep, ... <= vmax (with a tolerance of a thousandth
// of a step so 0.8 + 4 * 0.1 counts as <= 1.2 despite rounding).
int CountVelocities(const SeqSlamParams& p) {
  const double span =
      (static_cast<double>(p.v_max) - static_cast<double>(p.v_min)) / static_cast<double>(p.v_step);
  if (!(span < kMaxVelocities))
    return kMaxVelocities + 1;  // too many (or NaN): rejected, and no overflowing cast
  return static_cast<int>(std::floor(span + 1e-3)) + 1;
}

}  // namespace

const char* SeqSlamErrorMessage(SeqSlamError error) {
  switch (error) {
    case SeqSlamError::kOk:
      return "ok";
    case SeqSlamError::kBadSequenceLength:
      return "sequence length ds must be 1..1000 frames";
    case SeqSlamError::kBadVelocity:
      return "velocities need 0 <= vmin <= vmax <= 8 and vstep > 0 with at most 64 steps";
    case SeqSlamError::kBadContrastWindow:
      return "contrast enhancement window R must be 0..10000 frames";
    case SeqSlamError::kBadUniquenessWindow:
      return "uniqueness window Rwindow must be 0..10000 frames";
    case SeqSlamError::kBadDimension:
      return "descriptor length must be at least 1";
    case SeqSlamError::kBadCapacity:
      return "reference database capacity must be at least 1 frame";
    case SeqSlamError::kSizeMismatch:
      return "a buffer's size does not match the frame counts and descriptor length";
    case SeqSlamError::kDatabaseFull:
      return "reference database is full (raise its capacity)";
    case SeqSlamError::kNotInitialised:
      return "SeqSLAM engine used before Init succeeded";
    case SeqSlamError::kEmptyDatabase:
      return "no reference frames to match against";
    case SeqSlamError::kBadMaxAdvance:
      return "max_advance (route rows per query frame) must be 1..64";
    case SeqSlamError::kBadKeyframeFactor:
      return "keyframe noise factor must be 0..100 (0 keeps every taught frame)";
    case SeqSlamError::kRouteNotFinished:
      return "route not finished: call FinishRoute() after the last taught frame";
    case SeqSlamError::kRouteFinished:
      return "route already finished: clear it before adding taught frames";
    case SeqSlamError::kBadSearchWindow:
      return "search_window (route rows each side of the last best row) must be 0..1000000 "
             "(0: every row every frame)";
    case SeqSlamError::kBadRefreshFrames:
      return "refresh_frames (frames between refreshes of the rows outside search_window) must "
             "be 1..1000 with search_window > 0, and 0 without";
  }
  return "unknown SeqSLAM error";
}

SeqSlamError ValidateSeqSlamParams(const SeqSlamParams& p) {
  if (p.sequence_length < 1 || p.sequence_length > kMaxSequenceLength)
    return SeqSlamError::kBadSequenceLength;
  if (!(p.v_min >= 0.0f) || !(p.v_max >= p.v_min) || !(p.v_max <= 8.0f) || !(p.v_step > 0.0f))
    return SeqSlamError::kBadVelocity;
  if (CountVelocities(p) > kMaxVelocities)
    return SeqSlamError::kBadVelocity;
  if (p.contrast_window < 0 || p.contrast_window > kMaxWindow)
    return SeqSlamError::kBadContrastWindow;
  if (p.uniqueness_window < 0 || p.uniqueness_window > kMaxWindow)
    return SeqSlamError::kBadUniquenessWindow;
  return SeqSlamError::kOk;
}

// ---- Building blocks -------------------------------------------------------------------

namespace {

using simd::Abs4;
using simd::Float4;
using simd::Load4;

// Mean absolute difference of every row of a database to the query. `rows` says how the
// database holds its elements (float, bfloat16 or codes with a per-row scale):
// rows.Load8(r, i, ...) gives elements i .. i + 7 of row r as two Float4, rows.At(r, i) one
// element as a float.
//
// Eight independent partial sums per row (lane l sums elements l, l + 8, l + 16, ...),
// held as two SIMD registers, combined as ((0+1)+(2+3))+((4+5)+(6+7)). No sum is
// reordered (no fast-math), so every build gives the same floats, and a bfloat16 or code
// database gives exactly what its float conversion would. Two rows per pass share each
// load of the query, which does not fit in registers.
template <typename Rows>
void DifferenceRows(const Rows& rows, int dim, const float* q, std::span<float> out) {
  const std::size_t d = Sz(dim);
  const float inv_dim = 1.0f / static_cast<float>(dim);
  constexpr std::size_t kFloatsPerPass = 8;
  const std::size_t whole = d - d % kFloatsPerPass;
  const auto finish = [&](Float4 lo, Float4 hi, std::size_t r) {
    float lane[kFloatsPerPass];
    std::memcpy(lane, &lo, sizeof lo);
    std::memcpy(lane + 4, &hi, sizeof hi);
    for (std::size_t i = whole; i < d; ++i)
      lane[i - whole] += std::fabs(rows.At(r, i) - q[i]);
    const float sum =
        ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
    // Mean absolute difference (OpenSeqSLAM divides by the number of references instead:
    // a constant scale that the enhancement removes; note 3 in seqslam.h).
    return sum * inv_dim;
  };
  std::size_t r = 0;
  for (; r + 2 <= out.size(); r += 2) {
    Float4 a_lo = {}, a_hi = {}, b_lo = {}, b_hi = {};
    for (std::size_t i = 0; i < whole; i += kFloatsPerPass) {
      const Float4 q_lo = Load4(q + i), q_hi = Load4(q + i + 4);
      Float4 lo, hi;
      rows.Load8(r, i, &lo, &hi);
      a_lo += Abs4(lo - q_lo);
      a_hi += Abs4(hi - q_hi);
      rows.Load8(r + 1, i, &lo, &hi);
      b_lo += Abs4(lo - q_lo);
      b_hi += Abs4(hi - q_hi);
    }
    out[r] = finish(a_lo, a_hi, r);
    out[r + 1] = finish(b_lo, b_hi, r + 1);
  }
  for (; r < out.size(); ++r) {
    Float4 acc_lo = {}, acc_hi = {};
    for (std::size_t i = 0; i < whole; i += kFloatsPerPass) {
      Float4 lo, hi;
      rows.Load8(r, i, &lo, &hi);
      acc_lo += Abs4(lo - Load4(q + i));
      acc_hi += Abs4(hi - Load4(q + i + 4));
    }
    out[r] = finish(acc_lo, acc_hi, r);
  }
}

struct Float32Rows {
  const float* data;
  std::size_t dim;
  float At(std::size_t r, std::size_t i) const { return data[r * dim + i]; }
  void Load8(std::size_t r, std::size_t i, Float4* lo, Float4* hi) const {
    const float* p = data + r * dim + i;
    *lo = Load4(p);
    *hi = Load4(p + 4);
  }
};

struct BFloat16Rows {
  const std::uint16_t* data;
  std::size_t dim;
  float At(std::size_t r, std::size_t i) const { return FromBFloat16(data[r * dim + i]); }
  // Eight bfloat16 become eight floats by interleaving them with zero halves: the
  // bfloat16 lands in the high 16 bits of each 32-bit lane (punpcklwd / zip1).
  void Load8(std::size_t r, std::size_t i, Float4* lo, Float4* hi) const {
    static_assert(std::endian::native == std::endian::little, "lane layout assumes little endian");
    using Half8 = std::uint16_t __attribute__((vector_size(16)));
    Half8 h;
    std::memcpy(&h, data + r * dim + i, sizeof h);
    const Half8 zero = {};
    const Half8 low = __builtin_shuffle(zero, h, Half8{0, 8, 1, 9, 2, 10, 3, 11});
    const Half8 high = __builtin_shuffle(zero, h, Half8{4, 12, 5, 13, 6, 14, 7, 15});
    std::memcpy(lo, &low, sizeof low);
    std::memcpy(hi, &high, sizeof high);
  }
};

// Codes with a power-of-two scale per row: element = code * 2^exponent (16 bits) or
// code^2 * 2^exponent (8 bits, square law), exact in float (at most 16 significant bits
// times a power of two), so the differences are those of the decoded floats.
template <typename Code>
struct CodeRows {
  const Code* data;
  const std::int8_t* exponents;
  std::size_t dim;
  static constexpr bool kSquareLaw = sizeof(Code) == 1;
  float At(std::size_t r, std::size_t i) const {
    const float c = static_cast<float>(data[r * dim + i]);
    return (kSquareLaw ? c * c : c) * CodeScale(exponents[r]);
  }
  // Eight codes become eight floats without a lane at a time: the codes are zero-extended
  // to 32-bit lanes by interleaving them with zeros (punpcklbw / punpcklwd on SSE2, zip1 /
  // zip2 on NEON), then converted four at once as signed integers (cvtdq2ps / scvtf; SSE2
  // has no unsigned conversion, and a code below 2^16 is the same number either way).
  // __builtin_convertvector of four codes straight to floats was converted one lane at a
  // time by GCC 12 on both targets (docs/BENCHMARKS.md). Each conversion is exact, so the
  // floats are those of the scalar At().
  void Load8(std::size_t r, std::size_t i, Float4* lo, Float4* hi) const {
    static_assert(std::endian::native == std::endian::little, "lane layout assumes little endian");
    using Half8 = std::uint16_t __attribute__((vector_size(16)));
    using Int4 = std::int32_t __attribute__((vector_size(16)));
    const Code* p = data + r * dim + i;
    Half8 h;
    if constexpr (sizeof(Code) == 1) {
      // Eight bytes into the low half of a register (movq / ldr d), then to 16-bit lanes.
      using Byte16 = std::uint8_t __attribute__((vector_size(16)));
      using Word2 = std::uint64_t __attribute__((vector_size(16)));
      std::uint64_t eight;
      std::memcpy(&eight, p, sizeof eight);
      const Word2 words = {eight, 0};
      Byte16 b;
      std::memcpy(&b, &words, sizeof b);
      const Byte16 zero = {};
      const Byte16 wide = __builtin_shuffle(
          b, zero, Byte16{0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23});
      std::memcpy(&h, &wide, sizeof h);
    } else {
      std::memcpy(&h, p, sizeof h);
    }
    const Half8 zero = {};
    const Half8 low = __builtin_shuffle(h, zero, Half8{0, 8, 1, 9, 2, 10, 3, 11});
    const Half8 high = __builtin_shuffle(h, zero, Half8{4, 12, 5, 13, 6, 14, 7, 15});
    Int4 low_codes, high_codes;
    std::memcpy(&low_codes, &low, sizeof low);
    std::memcpy(&high_codes, &high, sizeof high);
    const float scale = CodeScale(exponents[r]);
    Float4 c_lo = __builtin_convertvector(low_codes, Float4);
    Float4 c_hi = __builtin_convertvector(high_codes, Float4);
    if constexpr (kSquareLaw) {
      c_lo *= c_lo;
      c_hi *= c_hi;
    }
    *lo = c_lo * scale;
    *hi = c_hi * scale;
  }
};

}  // namespace

void DifferenceColumn(std::span<const float> database, int dim, std::span<const float> query,
                      std::span<float> out) {
  DifferenceRows(Float32Rows{database.data(), Sz(dim)}, dim, query.data(), out);
}

std::uint16_t ToBFloat16(float value) {
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(value);
  if (std::isnan(value))
    return static_cast<std::uint16_t>((bits >> 16) | 0x40u);  // stays a NaN
  const std::uint32_t rounding = 0x7FFFu + ((bits >> 16) & 1u);
  return static_cast<std::uint16_t>((bits + rounding) >> 16);
}

float FromBFloat16(std::uint16_t value) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(value) << 16);
}

void DifferenceColumnBFloat16(std::span<const std::uint16_t> database, int dim,
                              std::span<const float> query, std::span<float> out) {
  DifferenceRows(BFloat16Rows{database.data(), Sz(dim)}, dim, query.data(), out);
}

template <typename Code>
void DifferenceColumnCodes(std::span<const Code> codes, std::span<const std::int8_t> exponents,
                           int dim, std::span<const float> query, std::span<float> out) {
  DifferenceRows(CodeRows<Code>{codes.data(), exponents.data(), Sz(dim)}, dim, query.data(), out);
}

template void DifferenceColumnCodes(std::span<const std::uint8_t>, std::span<const std::int8_t>,
                                    int, std::span<const float>, std::span<float>);
template void DifferenceColumnCodes(std::span<const std::uint16_t>, std::span<const std::int8_t>,
                                    int, std::span<const float>, std::span<float>);

std::size_t ReferenceRowBytes(ReferenceStorage storage, int dim) {
  switch (storage) {
    case ReferenceStorage::kFloat32:
      return 4 * Sz(dim);
    case ReferenceStorage::kBFloat16:
      return 2 * Sz(dim);
    case ReferenceStorage::kCodes8:
      return Sz(dim) + 1;
    case ReferenceStorage::kCodes16:
      return 2 * Sz(dim) + 1;
  }
  return 0;
}

float EnhancementShift(int n, int contrast_window) {
  const int half = contrast_window / 2;
  const int m = std::min(n, 2 * half + 1);
  if (m <= 1)
    return 0.0f;
  // |x_i - mean| / s <= (m - 1) / sqrt(m) for the sample std s of m values (Samuelson's
  // inequality), so adding this makes every enhanced value >= 0 (note 4 in seqslam.h).
  return static_cast<float>(static_cast<double>(m - 1) / std::sqrt(static_cast<double>(m)));
}

void ColumnEnhancer::Begin(int n, int contrast_window) {
  n_ = n;
  half_ = contrast_window / 2;
  shift_ = EnhancementShift(n, contrast_window);
  done_ = 0;
  m_ = 0;
  primed_ = false;
  sum_ = 0.0;
  sum_sq_ = 0.0;
}

int ColumnEnhancer::Advance(const float* d, int available, float* out) {
  // OpenSeqSLAM (doContrastEnhancement.m): rows a = max(1, i - R/2) .. b = min(N, i + R/2),
  // DD(i,:) = (D(i,:) - mean(D(a:b,:))) ./ std(D(a:b,:)). The window slides by one row per
  // step, so its sums are kept running (in double: a few ulp of drift over 100k rows)
  // instead of recomputed: O(N) rather than O(N * R).
  const int n = n_, half = half_;
  if (!primed_) {
    const int first_window = std::min(n, half + 1);  // rows 0 .. R/2: the window of row 0
    if (available < first_window)
      return done_;
    for (int r = 0; r < first_window; ++r) {
      const double v = static_cast<double>(d[Sz(r)]);
      sum_ += v;
      sum_sq_ += v * v;
      ++m_;
    }
    primed_ = true;
  }
  // Row i is finished (written, and the window slid on to row i + 1) once row
  // i + R/2 + 1 has arrived, or lies past the end of the column.
  const int limit = available >= n ? n : std::max(done_, available - half - 1);
  double sum = sum_, sum_sq = sum_sq_;
  int m = m_;
  while (done_ < limit) {
    const int first = done_;
    const int last = std::min(limit, first + kRowsPerPass);
    // Pass 1 (sequential): the window mean and variance of every row. The only
    // loop-carried work is one add per running sum: the rows entering and leaving the
    // window are combined first.
    double inv_m = 1.0 / m, inv_m1 = m > 1 ? 1.0 / (m - 1) : 0.0;
    int m_of_inv = m;
    const auto window_stats = [&](int i) {
      if (m != m_of_inv) {  // only near the ends of the column
        m_of_inv = m;
        inv_m = 1.0 / m;
        inv_m1 = m > 1 ? 1.0 / (m - 1) : 0.0;
      }
      const double mean = sum * inv_m;
      const double var = (sum_sq - sum * mean) * inv_m1;
      // A window whose values are all equal has variance 0 but the running sums leave a
      // rounding residue: anything below 1e-10 of the mean square counts as zero and the
      // entry is "no contrast" (0), never NaN or Inf (note 5). A 1-row window has no std.
      const double floor_var = 1e-10 * (sum_sq * inv_m) + 1e-30;
      mean_[i - first] = static_cast<float>(mean);
      var_[i - first] = static_cast<float>(m > 1 && var > floor_var ? var : 0.0);
    };
    // Rows whose window has a row entering and one leaving (the whole column but its
    // ends) take the branch-free path; it does the same arithmetic as the general one.
    const int middle_begin = std::clamp(half, first, last);
    const int middle_end = std::clamp(n - half - 1, middle_begin, last);
    const auto general_row = [&](int i) {
      window_stats(i);
      double delta = 0.0, delta_sq = 0.0;
      const int enter = i + half + 1, leave = i - half;
      if (enter < n) {
        const double v = static_cast<double>(d[Sz(enter)]);
        delta += v;
        delta_sq += v * v;
        ++m;
      }
      if (leave >= 0) {
        const double v = static_cast<double>(d[Sz(leave)]);
        delta -= v;
        delta_sq -= v * v;
        --m;
      }
      sum += delta;
      sum_sq += delta_sq;
    };
    for (int i = first; i < middle_begin; ++i)
      general_row(i);
    for (int i = middle_begin; i < middle_end; ++i) {
      window_stats(i);
      const double v_in = static_cast<double>(d[Sz(i + half + 1)]);
      const double v_out = static_cast<double>(d[Sz(i - half)]);
      sum += (0.0 + v_in) - v_out;
      sum_sq += (0.0 + v_in * v_in) - v_out * v_out;
    }
    for (int i = middle_end; i < last; ++i)
      general_row(i);
    // Pass 2 (independent per row, vectorises): z-score plus the shift (note 4). The
    // reciprocal square root is taken of max(var, tiny) so no lane ever divides by zero,
    // and the zero-variance rows are selected afterwards, without a branch.
    const int count = last - first;
    const float* __restrict d_rows = d + first;
    const float* __restrict means = mean_;
    const float* __restrict vars = var_;
    float* __restrict out_rows = out + first;
    const float shift = shift_;
    for (int i = 0; i < count; ++i) {
      const float var = vars[i];
      const float inv_std = 1.0f / std::sqrt(std::max(var, 1e-30f));
      const float z = (d_rows[i] - means[i]) * inv_std;
      out_rows[i] = (var > 0.0f ? z : 0.0f) + shift;
    }
    done_ = last;
  }
  sum_ = sum;
  sum_sq_ = sum_sq;
  m_ = m;
  return done_;
}

void EnhanceColumn(std::span<const float> d, int contrast_window, std::span<float> out) {
  ColumnEnhancer enhancer;
  const int n = static_cast<int>(d.size());
  enhancer.Begin(n, contrast_window);
  enhancer.Advance(d.data(), n, out.data());
}

// ---- Trajectory search -----------------------------------------------------------------

SeqSlamError TrajectorySearch::Init(const SeqSlamParams& params) {
  const SeqSlamError e = ValidateSeqSlamParams(params);
  if (e != SeqSlamError::kOk)
    return e;
  sequence_length_ = params.sequence_length;
  uniqueness_window_ = params.uniqueness_window;
  velocity_count_ = CountVelocities(params);
  velocities_.assign(Sz(velocity_count_), 0.0f);
  offsets_.assign(Sz(velocity_count_ * sequence_length_), 0);
  for (int k = 0; k < velocity_count_; ++k) {
    // Velocities step by v_step (OpenSeqSLAM steps by 1/ds; note 2).
    const double v = static_cast<double>(params.v_min) + k * static_cast<double>(params.v_step);
    velocities_[Sz(k)] = static_cast<float>(v);
    for (int j = 0; j < sequence_length_; ++j) {
      // OpenSeqSLAM: idx_add = floor((0:ds) .* v). The 1e-9 keeps 9.000000000000002 and
      // 8.999999999999998 (0.9 * 10 in binary) on the same side.
      offsets_[Sz(k * sequence_length_ + j)] = static_cast<int>(std::floor(j * v + 1e-9));
    }
  }
  distinct_.clear();
  max_offset_ = 0;
  for (int k = 0; k < velocity_count_; ++k) {
    const auto row = [&](int i) { return offsets_.begin() + i * sequence_length_; };
    bool seen = false;
    for (int earlier = 0; earlier < k && !seen; ++earlier)
      seen = std::equal(row(k), row(k) + sequence_length_, row(earlier));
    if (!seen)
      distinct_.push_back(k);
    max_offset_ = std::max(max_offset_, offset(k, sequence_length_ - 1));
  }
  return SeqSlamError::kOk;
}

SeqSlamMatch TrajectorySearch::Search(std::span<const float* const> columns, int n, int position,
                                      std::span<float> scores) const {
  ScoreStarts(columns, n, 0, n, scores);
  return Finish(columns, n, position, scores);
}

void TrajectorySearch::ScoreStarts(std::span<const float* const> columns, int n, int begin, int end,
                                   std::span<float> scores) const {
  const int len = sequence_length_;
  const int last = len - 1;
  // Starts are processed in blocks whose partial sums stay in L1; within a block the
  // innermost loop runs over consecutive starts, reading each column contiguously, so it
  // vectorises. Every score is summed j = 0, 1, ..., ds-1 in that order whatever the
  // blocking: batch and streaming give identical floats.
  constexpr int kBlock = 512;
  float acc[kBlock];
  for (int b0 = begin; b0 < end; b0 += kBlock) {
    const int b1 = std::min(end, b0 + kBlock);
    float* best = scores.data() + b0;
    std::fill(best, best + (b1 - b0), kInf);
    for (const int k : distinct_) {
      // A trajectory from start s must end inside the database: s + offset(k, ds-1) < n
      // (OpenSeqSLAM's +inf row does the same; note 7).
      const int s_end = std::min(b1, n - offset(k, last));
      if (s_end <= b0)
        continue;
      const int count = s_end - b0;
      std::fill(acc, acc + count, 0.0f);
      // Four columns per pass over the block: one load and store of the partial sums per
      // four adds. The adds stay in the order j = 0, 1, 2, ... (no reassociation).
      int j = 0;
      for (; j + 4 <= len; j += 4) {
        const float* c0 = columns[Sz(j)] + offset(k, j) + b0;
        const float* c1 = columns[Sz(j + 1)] + offset(k, j + 1) + b0;
        const float* c2 = columns[Sz(j + 2)] + offset(k, j + 2) + b0;
        const float* c3 = columns[Sz(j + 3)] + offset(k, j + 3) + b0;
        for (int i = 0; i < count; ++i)
          acc[i] = (((acc[i] + c0[i]) + c1[i]) + c2[i]) + c3[i];
      }
      for (; j < len; ++j) {
        const float* col = columns[Sz(j)] + offset(k, j) + b0;
        for (int i = 0; i < count; ++i)
          acc[i] += col[i];
      }
      for (int i = 0; i < count; ++i)
        best[i] = std::min(best[i], acc[i]);
    }
  }
}

SeqSlamMatch TrajectorySearch::Finish(std::span<const float* const> columns, int n, int position,
                                      std::span<const float> scores) const {
  SeqSlamMatch match;
  const int len = sequence_length_;
  const int last = len - 1;
  // Best start (the first on ties, as MATLAB's min).
  int best_s = -1;
  float best_score = kInf;
  for (int s = 0; s < n; ++s) {
    if (scores[Sz(s)] < best_score) {
      best_score = scores[Sz(s)];
      best_s = s;
    }
  }
  if (best_s < 0)
    return match;  // no trajectory fits in the database

  // Its velocity: recomputed with the same summation order, the first k reaching the min.
  int best_k = 0;
  for (int k = 0; k < velocity_count_; ++k) {
    if (best_s + offset(k, last) >= n)
      continue;
    float sum = 0.0f;
    for (int j = 0; j < len; ++j)
      sum += columns[Sz(j)][best_s + offset(k, j)];
    if (sum == best_score) {
      best_k = k;
      break;
    }
  }

  // Runner-up: the lowest score outside starts best_s - Rwindow/2 .. best_s + Rwindow/2
  // (OpenSeqSLAM's `window` / `not_window`).
  const int half = uniqueness_window_ / 2;
  const int w0 = best_s - half, w1 = best_s + half;
  float second = kInf;
  for (int s = 0; s < n; ++s) {
    if (s >= w0 && s <= w1)
      continue;
    second = std::min(second, scores[Sz(s)]);
  }

  match.valid = true;
  match.start = best_s;
  match.velocity = velocities_[Sz(best_k)];
  // The reference under query frame `position` on the best trajectory (note 6).
  match.reference = best_s + offset(best_k, position);
  match.row = match.reference;
  match.score = best_score;
  // No finite runner-up, or both zero: nothing shows this match is distinctive (note 8).
  if (second == kInf || !(second > 0.0f)) {
    match.uniqueness = 1.0f;
  } else {
    match.uniqueness = std::clamp(best_score / second, 0.0f, 1.0f);
  }
  match.confidence = 1.0f - match.uniqueness;
  return match;
}

// ---- Batch engine ----------------------------------------------------------------------

SeqSlamError ComputeDifferenceMatrix(std::span<const float> reference, std::span<const float> query,
                                     int dim, std::span<float> d) {
  if (dim < 1)
    return SeqSlamError::kBadDimension;
  const std::size_t dd = Sz(dim);
  if (reference.size() % dd != 0 || query.size() % dd != 0)
    return SeqSlamError::kSizeMismatch;
  const std::size_t n_ref = reference.size() / dd, n_query = query.size() / dd;
  if (d.size() != n_ref * n_query)
    return SeqSlamError::kSizeMismatch;
  for (std::size_t q = 0; q < n_query; ++q)
    DifferenceColumn(reference, dim, query.subspan(q * dd, dd), d.subspan(q * n_ref, n_ref));
  return SeqSlamError::kOk;
}

SeqSlamError EnhanceDifferenceMatrix(std::span<const float> d, int n_ref, int n_query,
                                     int contrast_window, std::span<float> out) {
  if (n_ref < 0 || n_query < 0 || d.size() != Sz(n_ref) * Sz(n_query) || out.size() != d.size())
    return SeqSlamError::kSizeMismatch;
  if (contrast_window < 0 || contrast_window > kMaxWindow)
    return SeqSlamError::kBadContrastWindow;
  for (int q = 0; q < n_query; ++q) {
    EnhanceColumn(d.subspan(Sz(q) * Sz(n_ref), Sz(n_ref)), contrast_window,
                  out.subspan(Sz(q) * Sz(n_ref), Sz(n_ref)));
  }
  return SeqSlamError::kOk;
}

SeqSlamError SeqSlamFromDifferences(std::span<const float> d, int n_ref, int n_query,
                                    const SeqSlamParams& params, SeqSlamWindow window,
                                    std::span<SeqSlamMatch> matches) {
  TrajectorySearch search;
  SeqSlamError e = search.Init(params);
  if (e != SeqSlamError::kOk)
    return e;
  if (matches.size() != Sz(n_query))
    return SeqSlamError::kSizeMismatch;
  std::vector<float> enhanced(d.size());
  e = EnhanceDifferenceMatrix(d, n_ref, n_query, params.contrast_window, enhanced);
  if (e != SeqSlamError::kOk)
    return e;
  const int len = params.sequence_length;
  std::vector<float> scores(Sz(n_ref));
  std::vector<const float*> columns(Sz(len));
  for (int t = 0; t < n_query; ++t) {
    matches[Sz(t)] = SeqSlamMatch{};
    // Centred: frames t - ds/2 .. t - ds/2 + ds - 1 (OpenSeqSLAM's N - ds/2 .. N + ds/2
    // with one frame fewer; note 1). Trailing: t - ds + 1 .. t.
    const int first = window == SeqSlamWindow::kCentred ? t - len / 2 : t - len + 1;
    if (first < 0 || first + len > n_query || n_ref == 0)
      continue;
    for (int j = 0; j < len; ++j)
      columns[Sz(j)] = enhanced.data() + Sz(first + j) * Sz(n_ref);
    matches[Sz(t)] = search.Search(columns, n_ref, t - first, scores);
  }
  return SeqSlamError::kOk;
}

SeqSlamError BatchSeqSlam(std::span<const float> reference, std::span<const float> query, int dim,
                          const SeqSlamParams& params, SeqSlamWindow window,
                          std::span<SeqSlamMatch> matches) {
  if (dim < 1)
    return SeqSlamError::kBadDimension;
  if (reference.size() % Sz(dim) != 0 || query.size() % Sz(dim) != 0)
    return SeqSlamError::kSizeMismatch;
  const int n_ref = static_cast<int>(reference.size() / Sz(dim));
  const int n_query = static_cast<int>(query.size() / Sz(dim));
  std::vector<float> d(Sz(n_ref) * Sz(n_query));
  const SeqSlamError e = ComputeDifferenceMatrix(reference, query, dim, d);
  if (e != SeqSlamError::kOk)
    return e;
  return SeqSlamFromDifferences(d, n_ref, n_query, params, window, matches);
}

// ---- Reference rows ---------------------------------------------------------------------

void ReferenceRows::Allocate(int dim, int capacity, ReferenceStorage storage) {
  dim_ = dim;
  storage_ = storage;
  float32_ = {};
  bfloat16_ = {};
  codes8_ = {};
  codes16_ = {};
  exponents_ = {};
  const std::size_t elements = Sz(capacity) * Sz(dim);
  switch (storage) {
    case ReferenceStorage::kFloat32:
      float32_.assign(elements, 0.0f);
      break;
    case ReferenceStorage::kBFloat16:
      bfloat16_.assign(elements, 0);
      break;
    case ReferenceStorage::kCodes8:
      codes8_.assign(elements, 0);
      exponents_.assign(Sz(capacity), 0);
      break;
    case ReferenceStorage::kCodes16:
      codes16_.assign(elements, 0);
      exponents_.assign(Sz(capacity), 0);
      break;
  }
}

void ReferenceRows::Store(int row, std::span<const float> descriptor) {
  const std::size_t at = Sz(row) * Sz(dim_);
  switch (storage_) {
    case ReferenceStorage::kFloat32:
      std::copy(descriptor.begin(), descriptor.end(), float32_.data() + at);
      break;
    case ReferenceStorage::kBFloat16:
      for (std::size_t i = 0; i < descriptor.size(); ++i)
        bfloat16_[at + i] = ToBFloat16(descriptor[i]);
      break;
    case ReferenceStorage::kCodes8:
      exponents_[Sz(row)] =
          EncodeCodes(descriptor, std::span<std::uint8_t>(codes8_.data() + at, Sz(dim_)));
      break;
    case ReferenceStorage::kCodes16:
      exponents_[Sz(row)] =
          EncodeCodes(descriptor, std::span<std::uint16_t>(codes16_.data() + at, Sz(dim_)));
      break;
  }
}

void ReferenceRows::Copy(int from, int to) {
  const std::size_t dim = Sz(dim_);
  switch (storage_) {
    case ReferenceStorage::kFloat32:
      std::copy_n(float32_.data() + Sz(from) * dim, dim, float32_.data() + Sz(to) * dim);
      break;
    case ReferenceStorage::kBFloat16:
      std::copy_n(bfloat16_.data() + Sz(from) * dim, dim, bfloat16_.data() + Sz(to) * dim);
      break;
    case ReferenceStorage::kCodes8:
      std::copy_n(codes8_.data() + Sz(from) * dim, dim, codes8_.data() + Sz(to) * dim);
      exponents_[Sz(to)] = exponents_[Sz(from)];
      break;
    case ReferenceStorage::kCodes16:
      std::copy_n(codes16_.data() + Sz(from) * dim, dim, codes16_.data() + Sz(to) * dim);
      exponents_[Sz(to)] = exponents_[Sz(from)];
      break;
  }
}

void ReferenceRows::Differences(std::span<const float> query, int first_row, int count,
                                float* out) const {
  const std::size_t at = Sz(first_row) * Sz(dim_);
  const std::size_t elements = Sz(count) * Sz(dim_);
  const std::span<float> column(out, Sz(count));
  switch (storage_) {
    case ReferenceStorage::kFloat32:
      DifferenceColumn(std::span<const float>(float32_.data() + at, elements), dim_, query, column);
      break;
    case ReferenceStorage::kBFloat16:
      DifferenceColumnBFloat16(std::span<const std::uint16_t>(bfloat16_.data() + at, elements),
                               dim_, query, column);
      break;
    case ReferenceStorage::kCodes8:
      DifferenceColumnCodes(std::span<const std::uint8_t>(codes8_.data() + at, elements),
                            std::span<const std::int8_t>(exponents_.data() + first_row, Sz(count)),
                            dim_, query, column);
      break;
    case ReferenceStorage::kCodes16:
      DifferenceColumnCodes(std::span<const std::uint16_t>(codes16_.data() + at, elements),
                            std::span<const std::int8_t>(exponents_.data() + first_row, Sz(count)),
                            dim_, query, column);
      break;
  }
}

void ReferenceRows::RowAsFloat(int row, float* out) const {
  const std::size_t dim = Sz(dim_), at = Sz(row) * dim;
  switch (storage_) {
    case ReferenceStorage::kFloat32:
      std::copy_n(float32_.data() + at, dim, out);
      break;
    case ReferenceStorage::kBFloat16:
      for (std::size_t k = 0; k < dim; ++k)
        out[k] = FromBFloat16(bfloat16_[at + k]);
      break;
    case ReferenceStorage::kCodes8:
      DecodeCodes(std::span<const std::uint8_t>(codes8_.data() + at, dim), exponents_[Sz(row)],
                  std::span<float>(out, dim));
      break;
    case ReferenceStorage::kCodes16:
      DecodeCodes(std::span<const std::uint16_t>(codes16_.data() + at, dim), exponents_[Sz(row)],
                  std::span<float>(out, dim));
      break;
  }
}

std::size_t ReferenceRows::AllocatedBytes() const {
  return sizeof(float) * float32_.size() + sizeof(std::uint16_t) * bfloat16_.size() +
         codes8_.size() + sizeof(std::uint16_t) * codes16_.size() + exponents_.size();
}

// ---- Streaming engine ------------------------------------------------------------------

SeqSlamError StreamingSeqSlam::Init(const SeqSlamParams& params, int dim, int capacity,
                                    ReferenceStorage storage) {
  SeqSlamError e = search_.Init(params);
  if (e != SeqSlamError::kOk)
    return e;
  if (dim < 1)
    return SeqSlamError::kBadDimension;
  if (capacity < 1)
    return SeqSlamError::kBadCapacity;
  params_ = params;
  dim_ = dim;
  capacity_ = capacity;
  const std::size_t len = Sz(params.sequence_length);
  rows_.Allocate(dim, capacity, storage);
  ring_.assign(len * Sz(capacity), 0.0f);
  difference_.assign(Sz(capacity), 0.0f);
  scores_.assign(Sz(capacity), 0.0f);
  order_.assign(len, nullptr);
  size_ = 0;
  ResetQueries();
  return SeqSlamError::kOk;
}

SeqSlamError StreamingSeqSlam::AddReference(std::span<const float> descriptor) {
  if (capacity_ == 0)
    return SeqSlamError::kNotInitialised;
  if (descriptor.size() != Sz(dim_))
    return SeqSlamError::kSizeMismatch;
  if (size_ >= capacity_)
    return SeqSlamError::kDatabaseFull;
  rows_.Store(size_, descriptor);
  ++size_;
  ResetQueries();
  return SeqSlamError::kOk;
}

void StreamingSeqSlam::ClearReferences() {
  size_ = 0;
  ResetQueries();
}

void StreamingSeqSlam::ResetQueries() {
  head_ = 0;
  count_ = 0;
}

SeqSlamError StreamingSeqSlam::Step(std::span<const float> query, SeqSlamMatch* out) {
  *out = SeqSlamMatch{};
  if (capacity_ == 0)
    return SeqSlamError::kNotInitialised;
  if (query.size() != Sz(dim_))
    return SeqSlamError::kSizeMismatch;
  if (size_ == 0)
    return SeqSlamError::kEmptyDatabase;
  const int n = size_;
  const int len = params_.sequence_length;
  float* diff = difference_.data();
  // Ring slots are `capacity` floats apart; only the first `size` of each are used. The
  // new column goes into slot head_; when it fills the ring, the search reads the ring
  // oldest first, which is then the slot after head_.
  float* slot = ring_.data() + Sz(head_) * Sz(capacity_);
  const bool full = count_ + 1 >= len;
  if (full) {
    for (int j = 0; j < len; ++j)
      order_[Sz(j)] = ring_.data() + Sz((head_ + 1 + j) % len) * Sz(capacity_);
  }
  // Difference, enhancement and search run a chunk of reference rows at a time: each
  // chunk's differences are enhanced as soon as their contrast windows are complete, and
  // the starts whose trajectories lie in enhanced rows are scored, while those rows are
  // still in L1/L2. Each step gives the same floats as whole-column passes would.
  constexpr int kRowsPerChunk = 1024;
  enhancer_.Begin(n, params_.contrast_window);
  const int max_offset = search_.max_offset();
  int read = 0, scored = 0;
  while (read < n) {
    const int next = std::min(n, read + kRowsPerChunk);
    rows_.Differences(query, read, next - read, diff + read);
    read = next;
    const int enhanced = enhancer_.Advance(diff, read, slot);
    if (full) {
      // Start s reads rows up to s + max_offset of the newest column.
      const int ready = enhanced == n ? n : std::max(scored, enhanced - max_offset);
      search_.ScoreStarts(order_, n, scored, ready, scores_);
      scored = ready;
    }
  }
  head_ = (head_ + 1) % len;
  count_ = std::min(count_ + 1, len);
  if (!full)
    return SeqSlamError::kOk;  // warming up: not a full sequence yet
  *out = search_.Finish(order_, n, len - 1, std::span<const float>(scores_.data(), Sz(n)));
  return SeqSlamError::kOk;
}

std::size_t StreamingSeqSlam::BytesPerReference(const SeqSlamParams& params, int dim,
                                                ReferenceStorage storage) {
  return ReferenceRowBytes(storage, dim) + sizeof(float) * (Sz(params.sequence_length) + 2);
}

std::size_t StreamingSeqSlam::AllocatedBytes() const {
  return rows_.AllocatedBytes() +
         sizeof(float) * (ring_.size() + difference_.size() + scores_.size()) +
         sizeof(const float*) * order_.size() +
         sizeof(int) * Sz(search_.velocity_count() * search_.sequence_length()) +
         sizeof(float) * Sz(search_.velocity_count());
}

}  // namespace skyloc::dsp
