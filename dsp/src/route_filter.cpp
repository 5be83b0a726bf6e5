#include "skyloc/dsp/route_filter.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include "float4.h"
#include "index_size.h"

namespace skyloc::dsp {
namespace {

// Two doubles as one SIMD register (SSE2 on x86-64, NEON on aarch64, plain code elsewhere).
using DoublePair = double __attribute__((vector_size(16)));
// Four row numbers, and the lane masks of a Float4 comparison.
using RowNumber4 = std::int32_t __attribute__((vector_size(16)));

// Adds diff[i] and its square to lane i & 3 of sum and sum_sq, i = 0 .. n - 1. Lanes 0, 1
// and 2, 3 go as two vectors of two doubles: each lane's adds come in the same order as
// one row at a time, so the sums are the same doubles on every machine.
void AccumulateSums(const float* diff, int n, double sum[4], double sum_sq[4]) {
  DoublePair s01 = {sum[0], sum[1]}, s23 = {sum[2], sum[3]};
  DoublePair q01 = {sum_sq[0], sum_sq[1]}, q23 = {sum_sq[2], sum_sq[3]};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    const DoublePair v01 = {static_cast<double>(diff[i]), static_cast<double>(diff[i + 1])};
    const DoublePair v23 = {static_cast<double>(diff[i + 2]), static_cast<double>(diff[i + 3])};
    s01 += v01;
    s23 += v23;
    q01 += v01 * v01;
    q23 += v23 * v23;
  }
  sum[0] = s01[0];
  sum[1] = s01[1];
  sum[2] = s23[0];
  sum[3] = s23[1];
  sum_sq[0] = q01[0];
  sum_sq[1] = q01[1];
  sum_sq[2] = q23[0];
  sum_sq[3] = q23[1];
  for (; i < n; ++i) {
    const double v = static_cast<double>(diff[i]);
    sum[i & 3] += v;
    sum_sq[i & 3] += v * v;
  }
}

// The lowest of cost[begin .. end - 1] (kInf when empty), four lanes at a time. Min4 keeps
// the lane's value against a NaN as std::min(lowest, cost) does, and which lane finds the
// minimum does not change its value.
float LowestOf(const float* cost, int begin, int end) {
  simd::Float4 lowest = {kInf, kInf, kInf, kInf};
  int i = begin;
  for (; i + 4 <= end; i += 4)
    lowest = simd::Min4(lowest, simd::Load4(cost + i));
  float m = std::min(std::min(lowest[0], lowest[1]), std::min(lowest[2], lowest[3]));
  for (; i < end; ++i)
    m = std::min(m, cost[i]);
  return m;
}

}  // namespace

SeqSlamError ValidateRouteFilterParams(const RouteFilterParams& p) {
  if (p.sequence_length < 1 || p.sequence_length > kMaxSequenceLength)
    return SeqSlamError::kBadSequenceLength;
  if (p.max_advance < 1 || p.max_advance > kMaxAdvance)
    return SeqSlamError::kBadMaxAdvance;
  if (p.uniqueness_window < 0 || p.uniqueness_window > kMaxWindow)
    return SeqSlamError::kBadUniquenessWindow;
  if (!(p.keyframe_noise_factor >= 0.0f && p.keyframe_noise_factor <= 100.0f))
    return SeqSlamError::kBadKeyframeFactor;
  if (p.search_window < 0 || p.search_window > kMaxSearchWindow)
    return SeqSlamError::kBadSearchWindow;
  if (p.search_window > 0 ? p.refresh_frames < 1 || p.refresh_frames > kMaxRefreshFrames
                          : p.refresh_frames != 0)
    return SeqSlamError::kBadRefreshFrames;
  return SeqSlamError::kOk;
}

SeqSlamError RouteFilter::Init(const RouteFilterParams& params, int dim, int capacity,
                               ReferenceStorage storage) {
  const SeqSlamError e = ValidateRouteFilterParams(params);
  if (e != SeqSlamError::kOk)
    return e;
  if (dim < 1)
    return SeqSlamError::kBadDimension;
  if (capacity < 1)
    return SeqSlamError::kBadCapacity;
  params_ = params;
  dim_ = dim;
  capacity_ = capacity;
  lambda_ =
      static_cast<float>(params.sequence_length - 1) / static_cast<float>(params.sequence_length);
  route_.Allocate(dim, capacity, storage);
  first_frame_.assign(Sz(capacity), 0);
  last_frame_.assign(Sz(capacity), 0);
  cost_.assign(Sz(capacity), 0.0f);
  previous_.assign(Sz(capacity), 0.0f);
  difference_.assign(Sz(capacity), 0.0f);
  key_.assign(Sz(dim), 0.0f);
  ClearReferences();
  return SeqSlamError::kOk;
}

SeqSlamError RouteFilter::AddReference(std::span<const float> descriptor) {
  if (capacity_ == 0)
    return SeqSlamError::kNotInitialised;
  if (finished_)
    return SeqSlamError::kRouteFinished;
  if (descriptor.size() != Sz(dim_))
    return SeqSlamError::kSizeMismatch;
  if (frames_ >= capacity_)
    return SeqSlamError::kDatabaseFull;
  route_.Store(frames_, descriptor);
  ++frames_;
  return SeqSlamError::kOk;
}

void RouteFilter::ClearReferences() {
  frames_ = 0;
  rows_ = 0;
  finished_ = false;
  keyframe_threshold_ = 0;
  ResetQueries();
}

void RouteFilter::ResetQueries() {
  steps_ = 0;
  refresh_phase_ = 0;
  track_row_ = -1;
  track_frames_ = 0;
}

SeqSlamError RouteFilter::FinishRoute() {
  if (capacity_ == 0)
    return SeqSlamError::kNotInitialised;
  ResetQueries();
  // The slots now hold rows, not frames: merging them again would read the wrong ones.
  if (finished_)
    return SeqSlamError::kOk;
  finished_ = true;
  rows_ = 0;
  keyframe_threshold_ = 0;
  const int n = frames_;
  if (n == 0)
    return SeqSlamError::kOk;  // Step() will say the route is empty
  // Frame i's descriptor as floats into key_ (exact for both storages).
  const auto load_key = [&](int i) { route_.RowAsFloat(i, key_.data()); };
  const bool merge = params_.keyframe_noise_factor > 0.0f && n >= 2;
  if (merge) {
    // The noise floor: the 10th percentile of consecutive differences (header, 1.). It
    // is capped at half the median, the change of a typical frame: on a route without
    // stops, whose frames all differ alike (or look unrelated), little or nothing merges.
    for (int i = 1; i < n; ++i) {
      load_key(i - 1);
      route_.Differences(key_, i, 1, &difference_[Sz(i - 1)]);
    }
    const auto begin = difference_.begin();
    const auto end = begin + (n - 1);
    const auto median = begin + (n - 1) / 2;
    std::nth_element(begin, median, end);
    const float half_median = 0.5f * *median;
    const auto floor = begin + (n - 1) / 10;
    std::nth_element(begin, floor, median);  // the 10th percentile is below the median
    keyframe_threshold_ = std::min(params_.keyframe_noise_factor * *floor, half_median);
  }
  // Compact in place: row r's descriptor moves to slot r (r <= i, so frame i is still in
  // slot i when it is read).
  int r = 0;
  first_frame_[0] = 0;
  last_frame_[0] = 0;
  load_key(0);
  for (int i = 1; i < n; ++i) {
    float d = 0;
    if (merge)
      route_.Differences(key_, i, 1, &d);
    if (merge && d <= keyframe_threshold_) {
      last_frame_[Sz(r)] = i;
      continue;
    }
    ++r;
    if (r != i)
      route_.Copy(i, r);
    first_frame_[Sz(r)] = i;
    last_frame_[Sz(r)] = i;
    if (merge)
      load_key(i);
  }
  rows_ = r + 1;
  return SeqSlamError::kOk;
}

void RouteFilter::CompareRows(std::span<const float> query) {
  const int n = rows_;
  float* diff = difference_.data();
  const int w = params_.search_window;
  // Every row on the first frame after a reset (no stale difference is ever used before
  // it was computed) and whenever the window covers the route.
  const bool windowed = w > 0 && steps_ > 0 && track_row_ >= 0 && 2 * std::int64_t{w} + 1 < n;
  if (!windowed) {
    route_.Differences(query, 0, n, diff);
    compared_[0] = 0;
    compared_[1] = n;
    compared_[2] = compared_[3] = 0;
    rows_compared_ = n;
    refresh_phase_ = 0;
    return;
  }
  const int w0 = std::max(0, track_row_ - w), w1 = std::min(n, track_row_ + w + 1);
  // Slice f of F: rows f n / F .. (f + 1) n / F - 1, so a cycle of F frames covers every
  // row exactly once and the slices differ by at most one row.
  const std::int64_t f = params_.refresh_frames;
  const int s0 = static_cast<int>(refresh_phase_ * std::int64_t{n} / f);
  const int s1 = static_cast<int>((refresh_phase_ + 1) * std::int64_t{n} / f);
  refresh_phase_ = static_cast<int>((refresh_phase_ + 1) % f);
  route_.Differences(query, w0, w1 - w0, diff + w0);
  rows_compared_ = w1 - w0;
  // The slice's rows outside the window: before it and after it.
  const int before_end = std::min(s1, w0), after_begin = std::max(s0, w1);
  if (s0 < before_end) {
    route_.Differences(query, s0, before_end - s0, diff + s0);
    rows_compared_ += before_end - s0;
  }
  if (after_begin < s1) {
    route_.Differences(query, after_begin, s1 - after_begin, diff + after_begin);
    rows_compared_ += s1 - after_begin;
  }
  compared_[0] = w0;
  compared_[1] = w1;
  compared_[2] = s0;
  compared_[3] = s1;
}

SeqSlamError RouteFilter::Step(std::span<const float> query, SeqSlamMatch* out) {
  *out = SeqSlamMatch{};
  if (capacity_ == 0)
    return SeqSlamError::kNotInitialised;
  if (query.size() != Sz(dim_))
    return SeqSlamError::kSizeMismatch;
  if (!finished_)
    return SeqSlamError::kRouteNotFinished;
  if (rows_ == 0)
    return SeqSlamError::kEmptyDatabase;
  const int n = rows_;
  const float* diff = difference_.data();

  // 1. Differences (every row, or the window's and a slice's: 6.), and the sums of the
  // whole column for the z-score. Four partial sums in a fixed order: the same doubles on
  // every machine, without one long dependent add chain.
  CompareRows(query);
  double sum[4] = {0, 0, 0, 0}, sum_sq[4] = {0, 0, 0, 0};
  AccumulateSums(diff, n, sum, sum_sq);
  const double total = (sum[0] + sum[1]) + (sum[2] + sum[3]);
  const double total_sq = (sum_sq[0] + sum_sq[1]) + (sum_sq[2] + sum_sq[3]);
  const double mean = total / n;
  const double var = (total_sq - total * mean) / n;
  // A column whose differences are all equal (one row, or a route of identical frames)
  // carries no evidence: z = 0 everywhere. The floor absorbs the rounding residue of the
  // sums, as in EnhanceColumn.
  const bool flat = !(var > 1e-10 * (total_sq / n) + 1e-30);
  const float mean_f = static_cast<float>(mean);
  const float inv_std = flat ? 0.0f : static_cast<float>(1.0 / std::sqrt(var));

  // 2. The filter update: cost(i) = z(i) + lambda * min over k = 0..K of previous(i - k),
  // with 3.'s best row (the first on ties) found on the way. Rows i >= K go 16 at a time
  // (four registers of four: the K + 1 loads of previous per register are in L1, and
  // nothing is stored between them); each row's minimum is taken in the order k = 1..K,
  // the costs and the best row are those of one row at a time, bit for bit.
  std::swap(cost_, previous_);
  const float* __restrict prev = previous_.data();
  float* __restrict cost = cost_.data();
  const float lambda = lambda_;
  const int advance = params_.max_advance;
  const bool first = steps_ == 0;
  // One row, its band over the rows that exist (i - k >= 0).
  const auto update_row = [&](int i) {
    float band = 0.0f;
    if (!first) {
      band = prev[i];
      for (int k = 1; k <= std::min(advance, i); ++k)
        band = prev[i - k] < band ? prev[i - k] : band;
    }
    const float z = (diff[Sz(i)] - mean_f) * inv_std;
    cost[i] = z + lambda * band;
  };
  const int head = std::min(n, advance);  // rows without K rows before them
  for (int i = 0; i < head; ++i)
    update_row(i);
  int best = 0;
  float best_cost = cost[0];
  for (int i = 1; i < head; ++i) {
    if (cost[i] < best_cost) {
      best_cost = cost[i];
      best = i;
    }
  }
  // Four lanes of the best so far: a lane takes a row only when strictly lower, so each
  // keeps its first minimum, and the lowest lane (the lowest index on ties) is the row
  // one row at a time would find. Lanes start at the head's best.
  using simd::Float4;
  Float4 lane_cost = {best_cost, best_cost, best_cost, best_cost};
  RowNumber4 lane_row = {best, best, best, best};
  const Float4 mean4 = {mean_f, mean_f, mean_f, mean_f};
  const Float4 inv_std4 = {inv_std, inv_std, inv_std, inv_std};
  const Float4 lambda4 = {lambda, lambda, lambda, lambda};
  const auto finish4 = [&](int i, Float4 band) {
    const Float4 z = (simd::Load4(diff + i) - mean4) * inv_std4;
    const Float4 c = z + lambda4 * band;
    simd::Store4(cost + i, c);
    const RowNumber4 lower = c < lane_cost;
    lane_cost = lower ? c : lane_cost;
    const RowNumber4 rows = {i, i + 1, i + 2, i + 3};
    lane_row = lower ? rows : lane_row;
  };
  int row = head;
  for (; row + 16 <= n; row += 16) {
    Float4 b0 = {}, b1 = {}, b2 = {}, b3 = {};
    if (!first) {
      b0 = simd::Load4(prev + row);
      b1 = simd::Load4(prev + row + 4);
      b2 = simd::Load4(prev + row + 8);
      b3 = simd::Load4(prev + row + 12);
      for (int k = 1; k <= advance; ++k) {
        const float* src = prev + row - k;
        b0 = simd::Min4(b0, simd::Load4(src));
        b1 = simd::Min4(b1, simd::Load4(src + 4));
        b2 = simd::Min4(b2, simd::Load4(src + 8));
        b3 = simd::Min4(b3, simd::Load4(src + 12));
      }
    }
    finish4(row, b0);
    finish4(row + 4, b1);
    finish4(row + 8, b2);
    finish4(row + 12, b3);
  }
  for (; row + 4 <= n; row += 4) {
    Float4 b = {};
    if (!first) {
      b = simd::Load4(prev + row);
      for (int k = 1; k <= advance; ++k)
        b = simd::Min4(b, simd::Load4(prev + row - k));
    }
    finish4(row, b);
  }
  for (int lane = 0; lane < 4; ++lane) {
    if (lane_cost[lane] < best_cost || (lane_cost[lane] == best_cost && lane_row[lane] < best)) {
      best_cost = lane_cost[lane];
      best = lane_row[lane];
    }
  }
  for (; row < n; ++row) {
    update_row(row);
    if (cost[row] < best_cost) {
      best_cost = cost[row];
      best = row;
    }
  }
  ++steps_;

  // 3. The runner-up: the best row outside the best's basin: the rows around it whose cost
  // rises monotonically away from it (a route sampled in time has alike neighbours, so
  // the basin can be wider than any fixed window), and at least +-uniqueness_window/2.
  const int half = params_.uniqueness_window / 2;
  int w0 = std::max(0, best - half), w1 = std::min(n - 1, best + half);
  for (int i = best; i > 0 && cost[i - 1] >= cost[i]; --i)
    w0 = std::min(w0, i - 1);
  for (int i = best; i + 1 < n && cost[i + 1] >= cost[i]; ++i)
    w1 = std::max(w1, i + 1);
  const float second = std::min(LowestOf(cost, 0, w0), LowestOf(cost, w1 + 1, n));

  out->valid = true;
  out->row = best;
  out->reference = ReportedFrame(best);
  out->start = -1;    // no straight trajectory: the path may change speed every frame
  out->velocity = 0;  // not estimated
  // Costs are sums over the filter's memory (1 + lambda + lambda^2 + ... = ds frames of
  // weight); per frame on average:
  out->score = static_cast<float>(static_cast<double>(best_cost) /
                                  static_cast<double>(params_.sequence_length));
  // The track: does this best row continue the last one as the motion allows (at most
  // +-uniqueness_window/2 rows back, the same place, and K + that forward)? When the best
  // row jumps, two paths of the filter are close and a frame ago the other one led; the
  // new leader has not yet shown it keeps leading.
  const bool continues =
      track_row_ >= 0 && best >= track_row_ - half && best <= track_row_ + advance + half;
  track_frames_ = continues ? track_frames_ + 1 : 0;
  track_row_ = best;
  double confidence = 0;
  if (second != kInf) {
    // The margin in column standard deviations of evidence, however many frames it took
    // to gather: the same threshold means the same evidence at every ds, and right after a
    // reset the confidence starts low and grows with the evidence. With no row outside
    // the window nothing shows this match is distinctive: confidence 0.
    const double margin = static_cast<double>(second) - static_cast<double>(best_cost);
    confidence = 1.0 - std::exp(-margin);
  }
  // Trust in a track grows over the 2 ds frames after it began: the filter's memory twice
  // over, the time a new path takes to gather its own evidence (docs/SEQSLAM.md, Design 4).
  confidence *= std::min(1.0, (track_frames_ + 1.0) / (2.0 * params_.sequence_length));
  out->confidence = static_cast<float>(confidence);
  out->uniqueness = 1.0f - out->confidence;
  return SeqSlamError::kOk;
}

int RouteFilter::ReportedFrame(int best) const {
  const int first = row_first_frame(best), last = row_last_frame(best);
  if (last == first)
    return first;
  // Doubles: the weights of near-equal costs decide the frame, and the same doubles come
  // out on every machine.
  const double best_cost = static_cast<double>(cost_[Sz(best)]);
  const auto weight = [&](int row) {
    return row < 0 || row >= rows_ ? 0.0
                                   : std::exp(best_cost - static_cast<double>(cost_[Sz(row)]));
  };
  const double before = weight(best - 1), after = weight(best + 1);
  const double p = (after - before) / (1.0 + before + after);
  return first + static_cast<int>(std::floor((0.5 + p) * (last - first)));
}

std::size_t RouteFilter::BytesPerReference(int dim, ReferenceStorage storage) {
  // Descriptor, two frame numbers, two cost columns, the difference column.
  return ReferenceRowBytes(storage, dim) + 2 * sizeof(int) + 3 * sizeof(float);
}

std::size_t RouteFilter::AllocatedBytes() const {
  return route_.AllocatedBytes() +
         sizeof(float) * (cost_.size() + previous_.size() + difference_.size() + key_.size()) +
         sizeof(int) * (first_frame_.size() + last_frame_.size());
}

}  // namespace skyloc::dsp
