#include "skyloc/dsp/seqslam.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

namespace skyloc::dsp {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::size_t Sz(int v) {
  return static_cast<std::size_t>(v);
}

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

// Four floats as one SIMD register (GCC/Clang vector extension: SSE2 on x86-64, NEON on
// aarch64, plain code elsewhere). Element-wise IEEE operations, so the results are the
// same as the scalar loop's.
using Float4 = float __attribute__((vector_size(16)));
using Bits4 = std::uint32_t __attribute__((vector_size(16)));

inline Float4 Load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline Float4 Abs4(Float4 v) {
  Bits4 bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits &= 0x7FFFFFFFu;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

}  // namespace

void DifferenceColumn(std::span<const float> database, int dim, std::span<const float> query,
                      std::span<float> out) {
  const std::size_t d = Sz(dim);
  const float inv_dim = 1.0f / static_cast<float>(dim);
  // Eight independent partial sums per row (lane l sums elements l, l + 8, l + 16, ...),
  // held as two SIMD registers, combined as ((0+1)+(2+3))+((4+5)+(6+7)). No sum is
  // reordered (no fast-math), so every build gives the same floats, and
  // DifferenceColumnBFloat16 (the same lanes written as scalar code) agrees bit for bit.
  // Two rows per pass share each load of the query, which does not fit in registers.
  constexpr std::size_t kLanes = 8;
  const std::size_t whole = d - d % kLanes;
  const float* q = query.data();
  const auto finish = [&](Float4 lo, Float4 hi, const float* row) {
    float lane[kLanes];
    std::memcpy(lane, &lo, sizeof lo);
    std::memcpy(lane + 4, &hi, sizeof hi);
    for (std::size_t i = whole; i < d; ++i)
      lane[i - whole] += std::fabs(row[i] - q[i]);
    const float sum =
        ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
    // Mean absolute difference (OpenSeqSLAM divides by the number of references instead:
    // a constant scale that the enhancement removes; note 3 in seqslam.h).
    return sum * inv_dim;
  };
  std::size_t r = 0;
  for (; r + 2 <= out.size(); r += 2) {
    const float* row0 = database.data() + r * d;
    const float* row1 = row0 + d;
    Float4 a_lo = {}, a_hi = {}, b_lo = {}, b_hi = {};
    for (std::size_t i = 0; i < whole; i += kLanes) {
      const Float4 q_lo = Load4(q + i), q_hi = Load4(q + i + 4);
      a_lo += Abs4(Load4(row0 + i) - q_lo);
      a_hi += Abs4(Load4(row0 + i + 4) - q_hi);
      b_lo += Abs4(Load4(row1 + i) - q_lo);
      b_hi += Abs4(Load4(row1 + i + 4) - q_hi);
    }
    out[r] = finish(a_lo, a_hi, row0);
    out[r + 1] = finish(b_lo, b_hi, row1);
  }
  for (; r < out.size(); ++r) {
    const float* row = database.data() + r * d;
    Float4 lo = {}, hi = {};
    for (std::size_t i = 0; i < whole; i += kLanes) {
      lo += Abs4(Load4(row + i) - Load4(q + i));
      hi += Abs4(Load4(row + i + 4) - Load4(q + i + 4));
    }
    out[r] = finish(lo, hi, row);
  }
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
  // The loop of DifferenceColumn with the conversion in front of each element: same lanes,
  // same order, so the result equals DifferenceColumn over the converted database.
  const std::size_t d = Sz(dim);
  const float inv_dim = 1.0f / static_cast<float>(dim);
  constexpr std::size_t kLanes = 8;
  const std::size_t whole = d - d % kLanes;
  const float* q = query.data();
  for (std::size_t r = 0; r < out.size(); ++r) {
    const std::uint16_t* row = database.data() + r * d;
    float lane[kLanes] = {};
    for (std::size_t i = 0; i < whole; i += kLanes) {
      // Widen eight elements at once (shift into the high half), then reinterpret: the
      // form the vectoriser turns into unpack + subtract + and-not.
      std::uint32_t bits[kLanes];
      for (std::size_t l = 0; l < kLanes; ++l)
        bits[l] = static_cast<std::uint32_t>(row[i + l]) << 16;
      float value[kLanes];
      std::memcpy(value, bits, sizeof value);
      for (std::size_t l = 0; l < kLanes; ++l)
        lane[l] += std::fabs(value[l] - q[i + l]);
    }
    for (std::size_t i = whole; i < d; ++i)
      lane[i - whole] += std::fabs(FromBFloat16(row[i]) - q[i]);
    const float sum =
        ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
    out[r] = sum * inv_dim;
  }
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

void EnhanceColumn(std::span<const float> d, int contrast_window, std::span<float> out,
                   std::span<float> scratch) {
  const int n = static_cast<int>(d.size());
  if (n == 0)
    return;
  // OpenSeqSLAM (doContrastEnhancement.m): rows a = max(1, i - R/2) .. b = min(N, i + R/2),
  // DD(i,:) = (D(i,:) - mean(D(a:b,:))) ./ std(D(a:b,:)). The window slides by one row per
  // step, so its sums are kept running (in double: a few ulp of drift over 100k rows)
  // instead of recomputed: O(N) rather than O(N * R).
  //
  // Pass 1 (sequential): the window mean into out[] and its variance into scratch[]. The
  // only loop-carried work is one add per running sum; the divisions by the window size
  // use reciprocals that change only near the ends.
  const int half = contrast_window / 2;
  const float shift = EnhancementShift(n, contrast_window);
  double sum = 0.0, sum_sq = 0.0;
  int m = 0;
  for (int r = 0; r <= std::min(n - 1, half); ++r) {
    const double v = static_cast<double>(d[Sz(r)]);
    sum += v;
    sum_sq += v * v;
    ++m;
  }
  int m_cached = -1;
  double inv_m = 0.0, inv_m1 = 0.0;
  for (int i = 0; i < n; ++i) {
    if (m != m_cached) {
      m_cached = m;
      inv_m = 1.0 / m;
      inv_m1 = m > 1 ? 1.0 / (m - 1) : 0.0;
    }
    const double mean = sum * inv_m;
    const double var = (sum_sq - sum * mean) * inv_m1;
    // A window whose values are all equal has variance 0 but the running sums leave a
    // rounding residue: anything below 1e-10 of the mean square counts as zero and the
    // entry is "no contrast" (0), never NaN or Inf (note 5). A 1-row window has no std.
    const double floor_var = 1e-10 * (sum_sq * inv_m) + 1e-30;
    out[Sz(i)] = static_cast<float>(mean);
    scratch[Sz(i)] = m > 1 && var > floor_var ? static_cast<float>(var) : 0.0f;
    // Slide to row i + 1: row i + half + 1 enters, row i - half leaves.
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
  }
  // Pass 2 (independent per row, vectorises): z-score plus the shift (note 4). The
  // reciprocal square root is taken of max(var, tiny) so no lane ever divides by zero.
  for (std::size_t i = 0; i < Sz(n); ++i) {
    const float var = scratch[i];
    const float inv_std = 1.0f / std::sqrt(std::max(var, 1e-30f));
    const float z = var > 0.0f ? (d[i] - out[i]) * inv_std : 0.0f;
    out[i] = z + shift;
  }
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
  return SeqSlamError::kOk;
}

SeqSlamMatch TrajectorySearch::Search(std::span<const float* const> columns, int n, int position,
                                      std::span<float> scores) const {
  SeqSlamMatch match;
  const int len = sequence_length_;
  const int last = len - 1;
  // Starts are processed in blocks whose partial sums stay in L1; within a block the
  // innermost loop runs over consecutive starts, reading each column contiguously, so it
  // vectorises. Every score is summed j = 0, 1, ..., ds-1 in that order whatever the
  // blocking: batch and streaming give identical floats.
  constexpr int kBlock = 512;
  float acc[kBlock];
  for (int b0 = 0; b0 < n; b0 += kBlock) {
    const int b1 = std::min(n, b0 + kBlock);
    float* best = scores.data() + b0;
    std::fill(best, best + (b1 - b0), kInf);
    for (int k = 0; k < velocity_count_; ++k) {
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
  std::vector<float> scratch(Sz(n_ref));
  for (int q = 0; q < n_query; ++q) {
    EnhanceColumn(d.subspan(Sz(q) * Sz(n_ref), Sz(n_ref)), contrast_window,
                  out.subspan(Sz(q) * Sz(n_ref), Sz(n_ref)), scratch);
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
  storage_ = storage;
  database_.clear();
  database_.shrink_to_fit();
  database_bf16_.clear();
  database_bf16_.shrink_to_fit();
  if (storage == ReferenceStorage::kFloat32) {
    database_.assign(Sz(capacity) * Sz(dim), 0.0f);
  } else {
    database_bf16_.assign(Sz(capacity) * Sz(dim), 0);
  }
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
  const std::size_t at = Sz(size_) * Sz(dim_);
  if (storage_ == ReferenceStorage::kFloat32) {
    std::copy(descriptor.begin(), descriptor.end(), database_.data() + at);
  } else {
    for (std::size_t i = 0; i < descriptor.size(); ++i)
      database_bf16_[at + i] = ToBFloat16(descriptor[i]);
  }
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
  const std::size_t n = Sz(size_);
  const int len = params_.sequence_length;
  std::span<float> diff(difference_.data(), n);
  if (storage_ == ReferenceStorage::kFloat32) {
    DifferenceColumn(std::span<const float>(database_.data(), n * Sz(dim_)), dim_, query, diff);
  } else {
    DifferenceColumnBFloat16(std::span<const std::uint16_t>(database_bf16_.data(), n * Sz(dim_)),
                             dim_, query, diff);
  }
  // Ring slots are `capacity` floats apart; only the first `size` of each are used.
  float* slot = ring_.data() + Sz(head_) * Sz(capacity_);
  // scores_ is free until the search: the enhancement's scratch.
  EnhanceColumn(diff, params_.contrast_window, std::span<float>(slot, n),
                std::span<float>(scores_.data(), n));
  head_ = (head_ + 1) % len;
  count_ = std::min(count_ + 1, len);
  if (count_ < len)
    return SeqSlamError::kOk;  // warming up: not a full sequence yet
  // Oldest first: the ring is full, so the oldest column is at head_.
  for (int j = 0; j < len; ++j)
    order_[Sz(j)] = ring_.data() + Sz((head_ + j) % len) * Sz(capacity_);
  *out = search_.Search(order_, size_, len - 1, std::span<float>(scores_.data(), n));
  return SeqSlamError::kOk;
}

std::size_t StreamingSeqSlam::BytesPerReference(const SeqSlamParams& params, int dim,
                                                ReferenceStorage storage) {
  const std::size_t element = storage == ReferenceStorage::kFloat32 ? 4 : 2;
  return element * Sz(dim) + sizeof(float) * (Sz(params.sequence_length) + 2);
}

std::size_t StreamingSeqSlam::AllocatedBytes() const {
  return sizeof(float) * (database_.size() + ring_.size() + difference_.size() + scores_.size()) +
         sizeof(std::uint16_t) * database_bf16_.size() + sizeof(const float*) * order_.size() +
         sizeof(int) * Sz(search_.velocity_count() * search_.sequence_length()) +
         sizeof(float) * Sz(search_.velocity_count());
}

}  // namespace skyloc::dsp
