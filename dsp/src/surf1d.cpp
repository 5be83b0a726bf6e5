#include "skyloc/dsp/surf1d.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
// is not inlined without SSE4.1): +-n/2 are left as they are. On whole columns (int) it
// gives the same values as on their doubles (for integers, x > n / 2.0 exactly when
// x > n / 2 in integer division, and x < -n / 2.0 when x < -(n / 2)), in integer
// instructions.
template <typename T>
T Fold(T x, T n, T half) {
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
      : n(columns), half(columns / 2), nd(columns), half_d(0.5 * columns) {}

  // x_b - x_a measured the short way round.
  int Difference(int a, int b) const { return Fold<int>(b - a, n, half); }

  // How far pair (xs, xt) lies off the line through pair (xs0, xt0) with slope scale,
  // folded the short way round.
  double Residual(int xs, int xt, int xs0, int xt0, double scale) const {
    const double predicted = scale * Difference(xs0, xs);
    return std::abs(Fold<double>(Difference(xt0, xt) - predicted, nd, half_d));
  }

  int n, half;
  double nd, half_d;
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
  std::array<double, kSurf1dDescriptorSize> v{};
  for (std::size_t k = 0; k < 2 * kDescriptorHalfSamples + 1; ++k) {
    const double centre = at[k + 1];
    const double dx = ((at[k + 2] - centre) - (centre - at[k])) / step_d;
    const double w = weights_[k];
    const std::size_t sub = k / kSamplesPerSubregion;
    v[2 * sub] += w * dx;
    v[2 * sub + 1] += w * std::abs(dx);
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
  double running = 0.0;
  const long n = n_;
  long source = ((-pad_ % n) + n) % n;
  for (std::size_t i = 1; i < integral_.size(); ++i) {
    running += static_cast<double>(strip[static_cast<std::size_t>(source)]);
    integral_[i] = running;
    if (++source == n)
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

  const auto magnitude = [&](int layer, int x) {  // x within [-1, n]
    if (x < 0) {
      x += n_;
    } else if (x >= n_) {
      x -= n_;
    }
    return std::abs(Response(layer, x));
  };
  int written = 0;
  for (int li = 0; li < layers; ++li) {
    for (int x = 0; x < n_; ++x) {
      const float m = magnitude(li, x);
      if (!(m > options_.threshold))
        continue;
      // Strictly above the neighbours before it, at least equal to those after it: a
      // plateau yields one feature, at the same place whatever the shift.
      if (!(m > magnitude(li, x - 1) && m >= magnitude(li, x + 1)))
        continue;
      if (options_.suppress_across_scale) {
        bool is_max = true;
        for (int dx = -1; dx <= 1 && is_max; ++dx) {
          if (li > 0 && !(m > magnitude(li - 1, x + dx)))
            is_max = false;
          if (li + 1 < layers && !(m >= magnitude(li + 1, x + dx)))
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
  const auto cap = static_cast<std::size_t>(max_features);
  for (StoredSide& side : stored_) {
    side.descriptors.assign(cap * kSurf1dDescriptorSize, 0.0f);
    side.positions.assign(cap, 0);
    side.count = 0;
  }
  has_stored_ = false;
  distances_.assign(cap, 0.0f);
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
  for (const Surf1dFeature& f : stored) {
    StoredSide& side = stored_[static_cast<std::size_t>(SideOf(f.laplacian_sign))];
    const auto s = static_cast<std::size_t>(side.count++);
    for (std::size_t k = 0; k < kSurf1dDescriptorSize; ++k)
      side.descriptors[k * static_cast<std::size_t>(capacity_) + s] = f.descriptor[k];
    side.positions[s] = f.position;
  }
  has_stored_ = true;
  return Surf1dError::kOk;
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
  // sign. First every squared distance, summed in the descriptor's order for each feature
  // (the loop runs across features, so it vectorises lane by lane without reordering any
  // sum), then one scan for the nearest two, whose branches are rarely taken: cheaper than
  // leaving each candidate early, whose data-dependent branches the predictor cannot learn.
  static_assert(kSurf1dDescriptorSize == 6, "the distance below is unrolled for 6 dimensions");
  const auto cap = static_cast<std::size_t>(capacity_);
  int matches = 0;
  for (const Surf1dFeature& t : test) {
    const StoredSide& side = stored_[static_cast<std::size_t>(SideOf(t.laplacian_sign))];
    const float q0 = t.descriptor[0], q1 = t.descriptor[1], q2 = t.descriptor[2];
    const float q3 = t.descriptor[3], q4 = t.descriptor[4], q5 = t.descriptor[5];
    const float* d0 = side.descriptors.data();
    const float* d1 = d0 + cap;
    const float* d2 = d1 + cap;
    const float* d3 = d2 + cap;
    const float* d4 = d3 + cap;
    const float* d5 = d4 + cap;
    float* distance = distances_.data();
    const int candidates = side.count;
    for (int s = 0; s < candidates; ++s) {
      float e = d0[s] - q0;
      float sum = e * e;
      e = d1[s] - q1;
      sum += e * e;
      e = d2[s] - q2;
      sum += e * e;
      e = d3[s] - q3;
      sum += e * e;
      e = d4[s] - q4;
      sum += e * e;
      e = d5[s] - q5;
      sum += e * e;
      distance[s] = sum;
    }
    float best = std::numeric_limits<float>::infinity();
    float second = best;
    int best_index = 0;
    for (int s = 0; s < candidates; ++s) {
      const float d = distance[s];
      if (d < second) {  // best <= second, so this is the only way in
        if (d < best) {
          second = best;
          best = d;
          best_index = s;
        } else {
          second = d;
        }
      }
    }
    if (!std::isfinite(second) || !(best < options_.ratio * options_.ratio * second))
      continue;
    best = std::sqrt(best);
    const auto m = static_cast<std::size_t>(matches++);
    pair_stored_[m] = side.positions[static_cast<std::size_t>(best_index)];
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
  const std::int32_t* xs = pair_stored_.data();
  const std::int32_t* xt = pair_test_.data();
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
    const int ds = circle.Difference(xs[i], xs[j]);
    const int dt = circle.Difference(xt[i], xt[j]);
    if (ds == 0)
      return false;
    const double scale = static_cast<double>(dt) / static_cast<double>(ds);
    // A mirrored horizon (b_s < 0) is not a view of the same place.
    if (!(scale >= 1.0 / max_scale && scale <= max_scale))
      return false;
    // A line that has already missed more pairs than the best line missed in all cannot
    // win (it needs at least as many inliers), so its count stops there.
    const int max_outliers = matches - best_inliers;
    const int xsi = xs[i], xti = xt[i];
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
    const double d = Wrap(static_cast<double>(xt[m]) - static_cast<double>(xs[m]), nd);
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
  result->displacement = Wrap(
      static_cast<double>(xt[best_anchor]) - best_scale * static_cast<double>(xs[best_anchor]), nd);
  double degrees = mean * 360.0 / nd;
  if (degrees >= 180.0)
    degrees -= 360.0;
  result->heading_offset_deg = degrees;
  return Surf1dError::kOk;
}

void LandmarkMatcher::MarkInliers(int anchor, double scale, int n) {
  const CircularColumns circle(n);
  const auto threshold = static_cast<double>(options_.inlier_threshold);
  const int xsi = pair_stored_[static_cast<std::size_t>(anchor)];
  const int xti = pair_test_[static_cast<std::size_t>(anchor)];
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
  return {pair_stored_[k], pair_test_[k], pair_distance_[k], last_model_ && best_inlier_[k] != 0};
}

}  // namespace skyloc::dsp
