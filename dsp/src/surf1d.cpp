#include "skyloc/dsp/surf1d.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "float4.h"

namespace skyloc::dsp {

namespace {

// Descriptor geometry (see surf1d.h): 15 samples, 3 sub-regions of 5.
constexpr int kDescriptorHalfSamples = 7;
constexpr int kSamplesPerSubregion = 5;
constexpr double kDescriptorSigmaSamples = 2.5;

// x - n * round(x / n): the circular difference, in [-n/2, n/2].
double Wrap(double x, double n) {
  return x - n * std::round(x / n);
}

// The same for |x| within a few n, without a library call in the RANSAC loop (std::round
// is not inlined without SSE4.1): +-half are left as they are.
double Fold(double x, double n, double half) {
  while (x > half)
    x -= n;
  while (x < -half)
    x += n;
  return x;
}

// SplitMix64: a small, seedable generator whose sequence is fixed by the seed on every
// platform (std:: distributions are not).
std::uint64_t NextRandom(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

int SideOf(std::int8_t laplacian_sign) {
  return laplacian_sign > 0 ? 0 : 1;
}

// Whether every feature has the Laplacian sign Detect gives (+1 or -1): the matcher files
// them by it.
bool SignsAreFromDetect(std::span<const Surf1dFeature> features) {
  return std::all_of(features.begin(), features.end(), [](const Surf1dFeature& f) {
    return f.laplacian_sign == 1 || f.laplacian_sign == -1;
  });
}

// RANSAC's arithmetic on a strip of n columns, one definition for the search and for the
// inliers it reports. Positions are whole columns, so their differences fold in integers
// (the values Fold gives on their doubles); only the line's prediction is a double.
struct CircularColumns {
  explicit CircularColumns(int columns)
      : nd(columns), half_columns(columns / 2), half_d(0.5 * columns) {}

  // x_b - x_a measured the short way round, for whole columns held as doubles: exact, and
  // folded at n / 2 in integer division as on ints (for whole x, x > n / 2 exactly when it
  // is above that integer), so the same values as on the ints, with no conversion.
  double Difference(double a, double b) const { return Fold(b - a, nd, half_columns); }

  // How far pair (xs, xt) lies off the line through pair (xs0, xt0) with slope scale,
  // folded the short way round.
  double Residual(double xs, double xt, double xs0, double xt0, double scale) const {
    const double predicted = scale * Difference(xs0, xs);
    return std::abs(Fold(Difference(xt0, xt) - predicted, nd, half_d));
  }

  double nd, half_columns, half_d;
};

}  // namespace

const char* Surf1dErrorMessage(Surf1dError error) {
  switch (error) {
    case Surf1dError::kOk:
      return "ok";
    case Surf1dError::kBadOptions:
      return "1D SURF options out of range: octaves and intervals must be 1..8 and the "
             "threshold a non-negative number";
    case Surf1dError::kStripTooShort:
      return "the horizon strip is too short for the largest 1D SURF filter: raise "
             "n_azimuth or use fewer octaves";
    case Surf1dError::kNotInitialised:
      return "1D SURF used before a successful Init";
    case Surf1dError::kSizeMismatch:
      return "the strip is not the length 1D SURF was initialised for";
    case Surf1dError::kTooManyFeatures:
      return "more stored or test features than the matcher was sized for: raise its "
             "max_features";
    case Surf1dError::kBadFeature:
      return "a 1D SURF feature's Laplacian sign is not +1 or -1: match features that "
             "Surf1d::Detect found";
  }
  return "unknown 1D SURF error";
}

int Surf1dMaxLobe(const Surf1dOptions& options) {
  return (1 << options.octaves) * options.intervals + 1;
}

Surf1dError Surf1d::Init(int n, const Surf1dOptions& options) {
  if (options.octaves < 1 || options.octaves > 8 || options.intervals < 1 ||
      options.intervals > 8 || !(options.threshold >= 0.0f)) {
    return Surf1dError::kBadOptions;
  }
  if (n <= 3 * Surf1dMaxLobe(options))
    return Surf1dError::kStripTooShort;
  std::vector<int> lobes;
  for (int o = 0; o < options.octaves; ++o) {
    for (int i = 0; i < options.intervals; ++i)
      lobes.push_back((2 << o) * (i + 1) + 1);
  }
  std::sort(lobes.begin(), lobes.end());
  lobes.erase(std::unique(lobes.begin(), lobes.end()), lobes.end());

  options_ = options;
  n_ = n;
  dropped_ = 0;
  lobes_ = std::move(lobes);
  const int max_lobe = lobes_.back();
  const long max_step = DescriptorStep(max_lobe);
  pad_ = std::max<long>((3 * max_lobe + 1) / 2 + 1, (kDescriptorHalfSamples + 1) * max_step + 1);
  integral_.assign(static_cast<std::size_t>(n + 2 * pad_) + 1, 0.0);
  for (int k = -kDescriptorHalfSamples; k <= kDescriptorHalfSamples; ++k) {
    const double kk = static_cast<double>(k);
    weights_[static_cast<std::size_t>(k + kDescriptorHalfSamples)] =
        std::exp(-kk * kk / (2.0 * kDescriptorSigmaSamples * kDescriptorSigmaSamples));
  }
  responses_.assign(lobes_.size() * static_cast<std::size_t>(n), 0.0f);
  magnitudes_.assign(lobes_.size() * (static_cast<std::size_t>(n) + 2), 0.0f);
  peaks_.assign((static_cast<std::size_t>(n) + 7) / 8 * 8, 0);
  steps_.clear();
  for (const int lobe : lobes_)
    steps_.push_back(DescriptorStep(lobe));
  return Surf1dError::kOk;
}

double Surf1d::BoxSum(long a, long b) const {
  return integral_[static_cast<std::size_t>(b + pad_)] -
         integral_[static_cast<std::size_t>(a + pad_)];
}

long Surf1d::DescriptorStep(int lobe) {
  return std::max(1L, std::lround(0.4 * lobe));
}

void Surf1d::Describe(int position, int layer, Surf1dFeature* feature) const {
  const long step = steps_[static_cast<std::size_t>(layer)];
  // Sample k (p = position + k step) is (BoxSum(p, p + step) - BoxSum(p - step, p)) / step:
  // neighbouring samples share box ends, so the integral is read once at each of the 17
  // points position + m step, m = -8..8, and the differences taken in the same order.
  constexpr int kPoints = 2 * kDescriptorHalfSamples + 3;
  std::array<double, kPoints> at;
  const double* base = integral_.data() + pad_ + position;
  for (int m = 0; m < kPoints; ++m)
    at[static_cast<std::size_t>(m)] = base[(m - kDescriptorHalfSamples - 1) * step];
  const auto step_d = static_cast<double>(step);
  // The weighted samples first, in a loop with no dependence between samples (SIMD lanes,
  // each the scalar's operations), then the sums in sample order.
  constexpr std::size_t kSamples = 2 * kDescriptorHalfSamples + 1;
  std::array<double, kSamples> weighted, weighted_abs;
  for (std::size_t k = 0; k < kSamples; ++k) {
    const double centre = at[k + 1];
    const double dx = ((at[k + 2] - centre) - (centre - at[k])) / step_d;
    weighted[k] = weights_[k] * dx;
    weighted_abs[k] = weights_[k] * std::abs(dx);
  }
  std::array<double, kSurf1dDescriptorSize> v{};
  for (std::size_t k = 0; k < kSamples; ++k) {
    const std::size_t sub = k / kSamplesPerSubregion;
    v[2 * sub] += weighted[k];
    v[2 * sub + 1] += weighted_abs[k];
  }
  double norm = 0.0;
  for (const double x : v)
    norm += x * x;
  norm = std::sqrt(norm);
  for (std::size_t i = 0; i < v.size(); ++i) {
    feature->descriptor[i] = norm > 0.0 ? static_cast<float>(v[i] / norm) : 0.0f;
  }
}

Surf1dError Surf1d::Detect(std::span<const float> strip, std::span<Surf1dFeature> features,
                           int* count) {
  *count = 0;
  if (n_ == 0)
    return Surf1dError::kNotInitialised;
  if (strip.size() != static_cast<std::size_t>(n_))
    return Surf1dError::kSizeMismatch;
  dropped_ = 0;

  // The integral of the periodic signal over [-pad, n + pad): every box the filters and
  // descriptors read is then two look-ups, with no wrap-around arithmetic.
  // In runs up to the strip's end, so the inner loop has no wrap-around test; the sums are
  // the same, in the same order.
  double running = 0.0;
  const long n = n_;
  auto source = static_cast<std::size_t>(((-pad_ % n) + n) % n);
  for (std::size_t i = 1; i < integral_.size();) {
    const std::size_t run = std::min(strip.size() - source, integral_.size() - i);
    for (std::size_t k = 0; k < run; ++k) {
      running += static_cast<double>(strip[source + k]);
      integral_[i + k] = running;
    }
    i += run;
    source = 0;
  }

  const int layers = static_cast<int>(lobes_.size());
  for (int li = 0; li < layers; ++li) {
    const long l = lobes_[static_cast<std::size_t>(li)];
    const long h = (l - 1) / 2;
    float* out = &responses_[static_cast<std::size_t>(li) * static_cast<std::size_t>(n_)];
    for (long x = 0; x < n_; ++x) {
      const double left = BoxSum(x - h - l, x - h);
      const double centre = BoxSum(x - h, x + h + 1);
      const double right = BoxSum(x + h + 1, x + h + 1 + l);
      out[x] = static_cast<float>((left + right - 2.0 * centre) / static_cast<double>(l));
    }
  }

  // The scan's tests read |response| with the columns either side, wrapped: one padded row
  // a layer, so no test computes a wrap-around index.
  const std::size_t row = static_cast<std::size_t>(n_) + 2;
  const auto columns = static_cast<std::size_t>(n_);
  for (std::size_t li = 0; li < static_cast<std::size_t>(layers); ++li) {
    const float* response = &responses_[li * columns];
    float* magnitude = &magnitudes_[li * row];
    magnitude[0] = std::abs(response[columns - 1]);
    for (std::size_t x = 0; x < columns; ++x)
      magnitude[x + 1] = std::abs(response[x]);
    magnitude[columns + 1] = std::abs(response[0]);
  }
  // Most columns fail the within-layer test (threshold, then a local maximum along the
  // strip), so it runs first over a whole layer, a byte a column in SIMD lanes; only the
  // columns it passes are visited, in ascending order, for the test across scales. The
  // comparisons are the ones a column-by-column scan made (a NaN fails each), so the
  // candidates and their order are the same.
  static_assert(std::endian::native == std::endian::little,
                "the peak bytes are read eight at a time, the lowest column in the lowest byte");
  const float threshold = options_.threshold;
  std::uint8_t* peaks = peaks_.data();
  int written = 0;
  for (int li = 0; li < layers; ++li) {
    const float* here = &magnitudes_[static_cast<std::size_t>(li) * row + 1];  // here[-1..n]
    const float* below = li > 0 ? here - row : nullptr;
    const float* above = li + 1 < layers ? here + row : nullptr;
    for (std::ptrdiff_t x = 0; x < static_cast<std::ptrdiff_t>(columns); ++x) {
      const float m = here[x];
      // Strictly above the neighbours before it, at least equal to those after it: a
      // plateau yields one feature, at the same place whatever the shift.
      peaks[x] =
          static_cast<std::uint8_t>((m > threshold) & (m > here[x - 1]) & (m >= here[x + 1]));
    }
    for (std::size_t word = 0; word < peaks_.size(); word += 8) {
      std::uint64_t bits;
      std::memcpy(&bits, peaks + word, sizeof bits);
      while (bits != 0) {
        const std::size_t byte = static_cast<std::size_t>(std::countr_zero(bits)) / 8;
        bits &= ~(std::uint64_t{0xff} << (8 * byte));
        const std::size_t xs = word + byte;
        const int x = static_cast<int>(xs);
        const float m = here[xs];
        if (options_.suppress_across_scale) {
          bool is_max = true;
          for (int dx = -1; dx <= 1 && is_max; ++dx) {
            if (below != nullptr && !(m > below[x + dx]))
              is_max = false;
            if (above != nullptr && !(m >= above[x + dx]))
              is_max = false;
          }
          if (!is_max)
            continue;
        }
        Surf1dFeature candidate;
        candidate.position = x;
        candidate.layer = li;
        candidate.lobe = lobes_[static_cast<std::size_t>(li)];
        candidate.response = Response(li, x);
        candidate.laplacian_sign = candidate.response > 0.0f ? std::int8_t{1} : std::int8_t{-1};
        if (static_cast<std::size_t>(written) < features.size()) {
          features[static_cast<std::size_t>(written++)] = candidate;
          continue;
        }
        ++dropped_;
        if (features.empty())
          continue;
        auto weakest = std::min_element(features.begin(), features.end(),
                                        [](const Surf1dFeature& a, const Surf1dFeature& b) {
                                          return std::abs(a.response) < std::abs(b.response);
                                        });
        if (std::abs(weakest->response) < m)
          *weakest = candidate;
      }
    }
  }
  auto kept = features.first(static_cast<std::size_t>(written));
  std::sort(kept.begin(), kept.end(), [](const Surf1dFeature& a, const Surf1dFeature& b) {
    return a.position != b.position ? a.position < b.position : a.layer < b.layer;
  });
  for (Surf1dFeature& f : kept)
    Describe(f.position, f.layer, &f);
  *count = written;
  return Surf1dError::kOk;
}

Surf1dError LandmarkMatcher::Init(int max_features, const LandmarkMatchOptions& options) {
  if (max_features < 1 || !(options.ratio > 0.0f) || !(options.min_distance > 0.0f) ||
      options.ransac_iterations < 1 || !(options.inlier_threshold >= 0.0f) ||
      !(options.max_scale >= 1.0f)) {
    return Surf1dError::kBadOptions;
  }
  options_ = options;
  capacity_ = max_features;
  stride_ = (max_features + 3) / 4 * 4;
  const auto cap = static_cast<std::size_t>(max_features);
  for (StoredSide& side : stored_) {
    side.descriptors.assign(static_cast<std::size_t>(stride_) * kSurf1dDescriptorSize, 0.0f);
    side.positions.assign(cap, 0);
    side.indices.assign(cap, 0);
    side.count = 0;
    side.key = 0;
    side.sorted = false;
  }
  has_stored_ = false;
  order_.assign(2 * cap, 0);
  pair_stored_.assign(cap, 0);
  pair_test_.assign(cap, 0);
  pair_distance_.assign(cap, 0.0f);
  best_inlier_.assign(cap, 0);
  last_pairs_ = 0;
  last_model_ = false;
  return Surf1dError::kOk;
}

Surf1dError LandmarkMatcher::SetStored(std::span<const Surf1dFeature> stored) {
  has_stored_ = false;
  for (StoredSide& side : stored_)
    side.count = 0;
  if (capacity_ == 0)
    return Surf1dError::kNotInitialised;
  if (stored.size() > static_cast<std::size_t>(capacity_))
    return Surf1dError::kTooManyFeatures;
  if (!SignsAreFromDetect(stored))
    return Surf1dError::kBadFeature;
  const auto stride = static_cast<std::size_t>(stride_);
  const auto cap = static_cast<std::size_t>(capacity_);
  // Each side's features in the given order (side s's indices from s * capacity_ in
  // order_), each component's range, and whether every component is finite.
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  std::array<int, 2> counts{};
  std::array<bool, 2> finites{true, true};
  std::array<std::array<float, kSurf1dDescriptorSize>, 2> lows{}, highs{};
  for (auto& low : lows)
    low.fill(kInfinity);
  for (auto& high : highs)
    high.fill(-kInfinity);
  for (std::size_t i = 0; i < stored.size(); ++i) {
    const Surf1dFeature& f = stored[i];
    const auto sign = static_cast<std::size_t>(SideOf(f.laplacian_sign));
    bool finite = true;
    for (std::size_t k = 0; k < kSurf1dDescriptorSize; ++k) {
      const float v = f.descriptor[k];
      finite &= std::fabs(v) <= std::numeric_limits<float>::max();  // false for NaN too
      lows[sign][k] = std::min(lows[sign][k], v);
      highs[sign][k] = std::max(highs[sign][k], v);
    }
    finites[sign] = finites[sign] && finite;
    order_[sign * cap + static_cast<std::size_t>(counts[sign]++)] = i;
  }
  for (int sign = 0; sign < 2; ++sign) {
    StoredSide& side = stored_[static_cast<std::size_t>(sign)];
    const int count = counts[static_cast<std::size_t>(sign)];
    const bool finite = finites[static_cast<std::size_t>(sign)];
    const std::array<float, kSurf1dDescriptorSize>& low = lows[static_cast<std::size_t>(sign)];
    const std::array<float, kSurf1dDescriptorSize>& high = highs[static_cast<std::size_t>(sign)];
    const auto order = order_.begin() + static_cast<std::ptrdiff_t>(sign) * capacity_;
    // The key: the component of the widest range (the first of equals). Sorted by its
    // value, as an integer whose order is the floats' (-0 before +0: equal keys in either
    // order), then by the index.
    std::size_t key = 0;
    if (finite) {
      for (std::size_t k = 1; k < kSurf1dDescriptorSize; ++k) {
        if (high[k] - low[k] > high[key] - low[key])
          key = k;
      }
      for (int slot = 0; slot < count; ++slot) {
        std::uint64_t& o = order[slot];
        // Before the key is added, o holds only the index (32 bits on any target).
        const auto bits =
            std::bit_cast<std::uint32_t>(stored[static_cast<std::size_t>(o)].descriptor[key]);
        const std::uint32_t sortable = (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
        o |= static_cast<std::uint64_t>(sortable) << 32;
      }
      std::sort(order, order + count);
    }
    for (int slot = 0; slot < count; ++slot) {
      const auto s = static_cast<std::size_t>(slot);
      const auto i = static_cast<std::size_t>(order[slot] & 0xFFFFFFFFu);
      const Surf1dFeature& f = stored[i];
      for (std::size_t k = 0; k < kSurf1dDescriptorSize; ++k)
        side.descriptors[k * stride + s] = f.descriptor[k];
      side.positions[s] = f.position;
      side.indices[s] = static_cast<std::int32_t>(i);
    }
    // The search reads whole groups of four slots.
    for (auto s = static_cast<std::size_t>(count); s % 4 != 0; ++s) {
      for (std::size_t k = 0; k < kSurf1dDescriptorSize; ++k)
        side.descriptors[k * stride + s] = kInfinity;
    }
    side.count = count;
    side.key = static_cast<int>(key);
    side.sorted = finite;
  }
  has_stored_ = true;
  return Surf1dError::kOk;
}

LandmarkMatcher::Nearest LandmarkMatcher::NearestTwo(const Surf1dFeature& test) const {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  if (!has_stored_)
    return {-1, kInfinity, kInfinity};
  const StoredSide& side = stored_[static_cast<std::size_t>(SideOf(test.laplacian_sign))];
  Nearest nearest = NearestOnSide(side, test, 0.0f);
  nearest.index =
      nearest.best < kInfinity ? side.indices[static_cast<std::size_t>(nearest.index)] : -1;
  return nearest;
}

// The nearest two by the straightforward scan's rule, in any order of visits: best the
// smallest distance, on ties the smallest index in the stored span; second the second
// smallest value, duplicates counted; a NaN distance is never below anything.
//
// Distances four slots at a time (element-wise IEEE operations, each lane summed in the
// descriptor's order: the scalar loop's bits), then kept in slot order. On a sorted side
// the search starts at the group of four holding the first slot whose key is >= the test
// feature's, q, and goes out both ways a group at a time, the nearer group first. A
// distance is a sum of non-negative rounded squares and rounding is monotonic, so it is at
// least its key term fl(fl(key - q)^2); along either way out that term does not decrease
// (fl(key - q) is monotonic in key), so a group's least is at its end nearest q. A way ends
// when that term is above `second` (no slot left there can change best or second) or equal
// to it while best < second (one could only equal second). With best == second a slot at
// that distance with a smaller index could still become best, so the search goes on.
//
// The ratio test (ratio2 > 0) needs only best, its slot, and whether best < ratio2 *
// second. Once the next term is above best, no slot left can change best or its slot, and
// the final second is at least min(second, term); with second finite (so the final one is
// too) and best < ratio2 * min(second, term), the test passes whatever is left (fl(ratio2 *
// x) is monotonic in x), so the search stops there.
LandmarkMatcher::Nearest LandmarkMatcher::NearestOnSide(const StoredSide& side,
                                                        const Surf1dFeature& test,
                                                        float ratio2) const {
  static_assert(kSurf1dDescriptorSize == 6, "the distance below is unrolled for 6 dimensions");
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  using simd::Float4;
  using simd::Load4;
  const auto stride = static_cast<std::size_t>(stride_);
  const float* d0 = side.descriptors.data();
  const float* d1 = d0 + stride;
  const float* d2 = d1 + stride;
  const float* d3 = d2 + stride;
  const float* d4 = d3 + stride;
  const float* d5 = d4 + stride;
  const std::int32_t* indices = side.indices.data();
  const std::array<float, kSurf1dDescriptorSize>& q = test.descriptor;
  const Float4 q0 = {q[0], q[0], q[0], q[0]}, q1 = {q[1], q[1], q[1], q[1]};
  const Float4 q2 = {q[2], q[2], q[2], q[2]}, q3 = {q[3], q[3], q[3], q[3]};
  const Float4 q4 = {q[4], q[4], q[4], q[4]}, q5 = {q[5], q[5], q[5], q[5]};
  const int count = side.count;
  float best = kInfinity;
  float second = kInfinity;
  int best_slot = 0;
  int best_index = std::numeric_limits<int>::max();
  const int groups = (count + 3) / 4;
  // Not sorted, or a test component not finite: every group, in slot order.
  const bool every =
      !side.sorted || !std::all_of(q.begin(), q.end(), [](float v) { return std::isfinite(v); });
  const float* keys = d0 + static_cast<std::size_t>(side.key) * stride;
  const float qk = q[static_cast<std::size_t>(side.key)];
  const auto term = [&](int slot) {
    const float e = keys[slot] - qk;
    return e * e;
  };
  // The next group each way: up (keys >= qk, least term at a group's first slot) and down
  // (keys < qk, at its last). The first group, up's, is always read (term -1).
  int up = 0, down = -1;
  if (!every && groups > 0) {
    const auto first = static_cast<int>(std::lower_bound(keys, keys + count, qk) - keys);
    up = std::min(first / 4, groups - 1);
    down = up - 1;
  }
  float up_term = -1.0f;
  float down_term = down >= 0 ? term(4 * down + 3) : kInfinity;
  while (up < groups || down >= 0) {
    const bool go_up = down < 0 || (up < groups && up_term <= down_term);
    const float bound = go_up ? up_term : down_term;
    if (bound > second || (bound == second && best < second))
      break;  // the other way's term is no smaller
    if (bound > best && second < kInfinity && best < ratio2 * std::min(second, bound))
      break;  // the ratio test passes
    const int group = go_up ? up++ : down--;
    if (go_up)
      up_term = every ? -1.0f : up < groups ? term(4 * up) : kInfinity;
    else
      down_term = down >= 0 ? term(4 * down + 3) : kInfinity;

    const auto i = static_cast<std::size_t>(4 * group);
    Float4 e = Load4(d0 + i) - q0;
    Float4 d = e * e;
    e = Load4(d1 + i) - q1;
    d += e * e;
    e = Load4(d2 + i) - q2;
    d += e * e;
    e = Load4(d3 + i) - q3;
    d += e * e;
    e = Load4(d4 + i) - q4;
    d += e * e;
    e = Load4(d5 + i) - q5;
    d += e * e;
    // Most groups have no slot within second: one vector comparison passes them.
    using Int4 = std::int32_t __attribute__((vector_size(16)));
    const Int4 within = d <= Float4{second, second, second, second};
    std::array<std::uint64_t, 2> halves{};
    std::memcpy(halves.data(), &within, sizeof within);
    if ((halves[0] | halves[1]) == 0)
      continue;
    const int lanes = std::min(4, count - 4 * group);
    for (int lane = 0; lane < lanes; ++lane) {
      const float v = d[lane];
      if (v <= second) {
        const int index = indices[i + static_cast<std::size_t>(lane)];
        if (v < best || (v == best && index < best_index)) {
          second = best;
          best = v;
          best_slot = 4 * group + lane;
          best_index = index;
        } else if (v < second) {
          second = v;
        }
      }
    }
  }
  return {best_slot, best, second};
}

Surf1dError LandmarkMatcher::Match(std::span<const Surf1dFeature> stored,
                                   std::span<const Surf1dFeature> test, int n,
                                   LandmarkMatch* result) {
  if (const Surf1dError e = SetStored(stored); e != Surf1dError::kOk) {
    *result = LandmarkMatch{};
    last_pairs_ = 0;
    last_model_ = false;
    return e;
  }
  return MatchStored(test, n, result);
}

Surf1dError LandmarkMatcher::MatchStored(std::span<const Surf1dFeature> test, int n,
                                         LandmarkMatch* result) {
  *result = LandmarkMatch{};
  last_pairs_ = 0;
  last_model_ = false;
  if (capacity_ == 0 || !has_stored_)
    return Surf1dError::kNotInitialised;
  if (n < 1)
    return Surf1dError::kSizeMismatch;
  if (test.size() > static_cast<std::size_t>(capacity_))
    return Surf1dError::kTooManyFeatures;
  if (!SignsAreFromDetect(test))
    return Surf1dError::kBadFeature;

  // Nearest neighbour with the ratio test among the stored features of the same Laplacian
  // sign (NearestOnSide).
  int matches = 0;
  for (const Surf1dFeature& t : test) {
    const StoredSide& side = stored_[static_cast<std::size_t>(SideOf(t.laplacian_sign))];
    const Nearest nearest = NearestOnSide(side, t, options_.ratio * options_.ratio);
    float best = nearest.best;
    const float second = nearest.second;
    if (!std::isfinite(second) || !(best < options_.ratio * options_.ratio * second))
      continue;
    best = std::sqrt(best);
    const auto m = static_cast<std::size_t>(matches++);
    pair_stored_[m] = side.positions[static_cast<std::size_t>(nearest.index)];
    pair_test_[m] = t.position;
    pair_distance_[m] = best;
    result->score += 1.0 / static_cast<double>(std::max(best, options_.min_distance));
  }
  result->matches = matches;
  last_pairs_ = matches;
  if (matches < 2)
    return Surf1dError::kOk;

  // RANSAC.
  const CircularColumns circle(n);
  const double nd = circle.nd;
  const double* xs = pair_stored_.data();
  const double* xt = pair_test_.data();
  const auto threshold = static_cast<double>(options_.inlier_threshold);
  const auto max_scale = static_cast<double>(options_.max_scale);
  int best_inliers = 0;
  double best_residual = std::numeric_limits<double>::infinity();
  double best_scale = 1.0;
  int best_anchor = -1;
  // The line through pairs i and j, anchored at i, against the best so far (most inliers,
  // then the smallest residual sum; the first of equals stays). True when no later line can
  // do better: every pair on it with no residual.
  const auto try_line = [&](int i, int j) {
    // Differences measured the short way round, anchored at match i.
    const double ds = circle.Difference(xs[i], xs[j]);
    const double dt = circle.Difference(xt[i], xt[j]);
    if (ds == 0)
      return false;
    const double scale = dt / ds;
    // A mirrored horizon (b_s < 0) is not a view of the same place.
    if (!(scale >= 1.0 / max_scale && scale <= max_scale))
      return false;
    // A line that has already missed more pairs than the best line missed in all cannot
    // win (it needs at least as many inliers), so its count stops there.
    const int max_outliers = matches - best_inliers;
    const double xsi = xs[i], xti = xt[i];
    int inliers = 0, outliers = 0;
    double residual_sum = 0.0;
    for (int m = 0; m < matches; ++m) {
      const double residual = circle.Residual(xs[m], xt[m], xsi, xti, scale);
      if (residual <= threshold) {
        ++inliers;
        residual_sum += residual;
      } else if (++outliers > max_outliers) {
        return false;
      }
    }
    if (inliers > best_inliers || (inliers == best_inliers && residual_sum < best_residual)) {
      best_inliers = inliers;
      best_residual = residual_sum;
      best_scale = scale;
      best_anchor = i;
      return inliers == matches && residual_sum == 0.0;
    }
    return false;
  };
  const int budget = options_.ransac_iterations;
  const auto lines = static_cast<std::int64_t>(matches) * (matches - 1) / 2;
  if (lines <= budget) {
    // No more distinct lines than draws: each once, i < j, anchored at i.
    bool done = false;
    for (int i = 0; i < matches && !done; ++i) {
      for (int j = i + 1; j < matches && !done; ++j)
        done = try_line(i, j);
    }
  } else {
    const auto count = static_cast<std::uint64_t>(matches);
    std::uint64_t state = options_.seed;
    for (int it = 0; it < budget; ++it) {
      const auto i = static_cast<int>(NextRandom(&state) % count);
      auto j = static_cast<int>(NextRandom(&state) % (count - 1));
      if (j >= i)
        ++j;
      if (try_line(i, j))
        break;
    }
  }
  if (best_inliers < 2)
    return Surf1dError::kOk;
  MarkInliers(best_anchor, best_scale, n);
  last_model_ = true;

  // Circular mean of the inliers' displacement, unwrapped around the first inlier's.
  double reference = 0.0;
  bool have_reference = false;
  double sum = 0.0;
  for (int m = 0; m < matches; ++m) {
    if (!best_inlier_[static_cast<std::size_t>(m)])
      continue;
    const double d = Wrap(xt[m] - xs[m], nd);
    if (!have_reference) {
      reference = d;
      have_reference = true;
    }
    sum += reference + Wrap(d - reference, nd);
    result->ransac_score +=
        1.0 / static_cast<double>(
                  std::max(pair_distance_[static_cast<std::size_t>(m)], options_.min_distance));
  }
  const double mean = Wrap(sum / best_inliers, nd);
  result->model_found = true;
  result->inliers = best_inliers;
  result->scale = best_scale;
  result->displacement = Wrap(xt[best_anchor] - best_scale * xs[best_anchor], nd);
  double degrees = mean * 360.0 / nd;
  if (degrees >= 180.0)
    degrees -= 360.0;
  result->heading_offset_deg = degrees;
  return Surf1dError::kOk;
}

void LandmarkMatcher::MarkInliers(int anchor, double scale, int n) {
  const CircularColumns circle(n);
  const auto threshold = static_cast<double>(options_.inlier_threshold);
  const double xsi = pair_stored_[static_cast<std::size_t>(anchor)];
  const double xti = pair_test_[static_cast<std::size_t>(anchor)];
  for (int m = 0; m < last_pairs_; ++m) {
    const auto k = static_cast<std::size_t>(m);
    best_inlier_[k] =
        circle.Residual(pair_stored_[k], pair_test_[k], xsi, xti, scale) <= threshold ? 1 : 0;
  }
}

LandmarkMatcher::MatchedPair LandmarkMatcher::last_pair(int i) const {
  if (i < 0 || i >= last_pairs_)
    return {};
  const auto k = static_cast<std::size_t>(i);
  return {static_cast<std::int32_t>(pair_stored_[k]), static_cast<std::int32_t>(pair_test_[k]),
          pair_distance_[k], last_model_ && best_inlier_[k] != 0};
}

}  // namespace skyloc::dsp
