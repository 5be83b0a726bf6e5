#include "skyloc/dsp/route_filter.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

#include "float4.h"
#include "index_size.h"

namespace skyloc::dsp {
namespace {

// Rows per pass of the filter update: the band minimum works on a block of rows that
// stays in L1 while it is read K + 1 times.
constexpr int kBlockRows = 1024;

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
  float* diff = difference_.data();

  // 1. Differences, and their sums for the z-score. Four partial sums in a fixed order:
  // the same doubles on every machine, without one long dependent add chain.
  double sum[4] = {0, 0, 0, 0}, sum_sq[4] = {0, 0, 0, 0};
  for (int r0 = 0; r0 < n; r0 += kBlockRows) {
    const int count = std::min(kBlockRows, n - r0);
    route_.Differences(query, r0, count, diff + r0);
    for (int i = r0; i < r0 + count; ++i) {
      const double v = static_cast<double>(diff[Sz(i)]);
      sum[i & 3] += v;
      sum_sq[i & 3] += v * v;
    }
  }
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

  // 2. The filter update: cost(i) = z(i) + lambda * min over k = 0..K of previous(i - k).
  std::swap(cost_, previous_);
  const float* __restrict prev = previous_.data();
  float* __restrict cost = cost_.data();
  const float lambda = lambda_;
  const int advance = params_.max_advance;
  const bool first = steps_ == 0;
  for (int r0 = 0; r0 < n; r0 += kBlockRows) {
    const int count = std::min(kBlockRows, n - r0);
    float band[kBlockRows];
    if (first) {
      std::fill(band, band + count, 0.0f);
    } else {
      std::copy_n(prev + r0, count, band);
      for (int k = 1; k <= advance; ++k) {
        const int lo = std::max(r0, k);  // rows i >= k have a row i - k
        float* dst = band + (lo - r0);
        const float* src = prev + (lo - k);
        const int m = r0 + count - lo;
        // Four rows at a time, branch-free: a scalar std::min compiles to a compare and a
        // branch that random costs mispredict half the time.
        int i = 0;
        for (; i + 4 <= m; i += 4)
          simd::Store4(dst + i, simd::Min4(simd::Load4(dst + i), simd::Load4(src + i)));
        for (; i < m; ++i)
          dst[i] = src[i] < dst[i] ? src[i] : dst[i];
      }
    }
    for (int i = 0; i < count; ++i) {
      const float z = (diff[Sz(r0 + i)] - mean_f) * inv_std;
      cost[r0 + i] = z + lambda * band[i];
    }
  }
  ++steps_;

  // 3. The best row (the first on ties) and the best row outside its window.
  int best = 0;
  float best_cost = cost[0];
  for (int i = 1; i < n; ++i) {
    if (cost[i] < best_cost) {
      best_cost = cost[i];
      best = i;
    }
  }
  // The runner-up is the best row outside the best's basin: the rows around it whose cost
  // rises monotonically away from it (a route sampled in time has alike neighbours, so
  // the basin can be wider than any fixed window), and at least +-uniqueness_window/2.
  const int half = params_.uniqueness_window / 2;
  int w0 = std::max(0, best - half), w1 = std::min(n - 1, best + half);
  for (int i = best; i > 0 && cost[i - 1] >= cost[i]; --i)
    w0 = std::min(w0, i - 1);
  for (int i = best; i + 1 < n && cost[i + 1] >= cost[i]; ++i)
    w1 = std::max(w1, i + 1);
  float second = kInf;
  for (int i = 0; i < w0; ++i)
    second = std::min(second, cost[i]);
  for (int i = w1 + 1; i < n; ++i)
    second = std::min(second, cost[i]);

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
