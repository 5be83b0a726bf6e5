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
// is not inlined without SSE4.1): +-n/2 are left as they are.
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

float SquaredDistance(const Surf1dFeature& a, const Surf1dFeature& b) {
  float sum = 0.0f;
  for (int i = 0; i < kSurf1dDescriptorSize; ++i) {
    const float d =
        a.descriptor[static_cast<std::size_t>(i)] - b.descriptor[static_cast<std::size_t>(i)];
    sum += d * d;
  }
  return sum;
}

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
      return "more test features than the matcher was sized for: raise its max_features";
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
  const long max_step = std::max(1L, std::lround(0.4 * max_lobe));
  pad_ = std::max<long>((3 * max_lobe + 1) / 2 + 1, (kDescriptorHalfSamples + 1) * max_step + 1);
  integral_.assign(static_cast<std::size_t>(n + 2 * pad_) + 1, 0.0);
  for (int k = -kDescriptorHalfSamples; k <= kDescriptorHalfSamples; ++k) {
    const double kk = static_cast<double>(k);
    weights_[static_cast<std::size_t>(k + kDescriptorHalfSamples)] =
        std::exp(-kk * kk / (2.0 * kDescriptorSigmaSamples * kDescriptorSigmaSamples));
  }
  responses_.assign(lobes_.size() * static_cast<std::size_t>(n), 0.0f);
  return Surf1dError::kOk;
}

double Surf1d::BoxSum(long a, long b) const {
  return integral_[static_cast<std::size_t>(b + pad_)] -
         integral_[static_cast<std::size_t>(a + pad_)];
}

void Surf1d::Describe(int position, int lobe, Surf1dFeature* feature) const {
  const long step = std::max(1L, std::lround(0.4 * lobe));
  std::array<double, kSurf1dDescriptorSize> v{};
  for (int k = -kDescriptorHalfSamples; k <= kDescriptorHalfSamples; ++k) {
    const long p = position + k * step;
    const double dx = (BoxSum(p, p + step) - BoxSum(p - step, p)) / static_cast<double>(step);
    const double w = weights_[static_cast<std::size_t>(k + kDescriptorHalfSamples)];
    const auto sub = static_cast<std::size_t>((k + kDescriptorHalfSamples) / kSamplesPerSubregion);
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
    Describe(f.position, f.lobe, &f);
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
  pairs_.assign(cap, Pair{0.0, 0.0, 0.0f});
  inlier_.assign(cap, 0);
  best_inlier_.assign(cap, 0);
  return Surf1dError::kOk;
}

Surf1dError LandmarkMatcher::Match(std::span<const Surf1dFeature> stored,
                                   std::span<const Surf1dFeature> test, int n,
                                   LandmarkMatch* result) {
  *result = LandmarkMatch{};
  last_pairs_ = 0;
  last_model_ = false;
  if (capacity_ == 0)
    return Surf1dError::kNotInitialised;
  if (n < 1)
    return Surf1dError::kSizeMismatch;
  if (test.size() > static_cast<std::size_t>(capacity_))
    return Surf1dError::kTooManyFeatures;

  // Nearest neighbour with the ratio test; only features of the same Laplacian sign compete.
  int matches = 0;
  for (std::size_t t = 0; t < test.size(); ++t) {
    float best = std::numeric_limits<float>::infinity();
    float second = best;
    std::size_t best_index = 0;
    for (std::size_t s = 0; s < stored.size(); ++s) {
      if (stored[s].laplacian_sign != test[t].laplacian_sign)
        continue;
      const float d = SquaredDistance(stored[s], test[t]);  // squared until the end
      if (d < best) {
        second = best;
        best = d;
        best_index = s;
      } else if (d < second) {
        second = d;
      }
    }
    if (!std::isfinite(second) || !(best < options_.ratio * options_.ratio * second))
      continue;
    best = std::sqrt(best);
    pairs_[static_cast<std::size_t>(matches++)] = {static_cast<double>(stored[best_index].position),
                                                   static_cast<double>(test[t].position), best};
    result->score += 1.0 / static_cast<double>(std::max(best, options_.min_distance));
  }
  result->matches = matches;
  last_pairs_ = matches;
  if (matches < 2)
    return Surf1dError::kOk;

  const double nd = n;
  const double half = 0.5 * nd;
  const auto xs = [&](int m) { return pairs_[static_cast<std::size_t>(m)].x_stored; };
  const auto xt = [&](int m) { return pairs_[static_cast<std::size_t>(m)].x_test; };
  const auto count = static_cast<std::uint64_t>(matches);
  std::uint64_t state = options_.seed;
  int best_inliers = 0;
  double best_residual = std::numeric_limits<double>::infinity();
  double best_scale = 1.0;
  double best_displacement = 0.0;
  for (int it = 0; it < options_.ransac_iterations; ++it) {
    const auto i = static_cast<int>(NextRandom(&state) % count);
    auto j = static_cast<int>(NextRandom(&state) % (count - 1));
    if (j >= i)
      ++j;
    // Differences measured the short way round, anchored at match i.
    const double ds = Fold(xs(j) - xs(i), nd, half);
    const double dt = Fold(xt(j) - xt(i), nd, half);
    if (ds == 0.0)
      continue;
    const double scale = dt / ds;
    const auto max_scale = static_cast<double>(options_.max_scale);
    // A mirrored horizon (b_s < 0) is not a view of the same place.
    if (!(scale >= 1.0 / max_scale && scale <= max_scale)) {
      continue;
    }
    int inliers = 0;
    double residual_sum = 0.0;
    for (int m = 0; m < matches; ++m) {
      const double predicted = scale * Fold(xs(m) - xs(i), nd, half);
      const double residual = std::abs(Fold(Fold(xt(m) - xt(i), nd, half) - predicted, nd, half));
      const bool in = residual <= static_cast<double>(options_.inlier_threshold);
      inlier_[static_cast<std::size_t>(m)] = in ? 1 : 0;
      if (in) {
        ++inliers;
        residual_sum += residual;
      }
    }
    if (inliers > best_inliers || (inliers == best_inliers && residual_sum < best_residual)) {
      best_inliers = inliers;
      best_residual = residual_sum;
      best_scale = scale;
      best_displacement = Wrap(xt(i) - scale * xs(i), nd);
      std::copy(inlier_.begin(), inlier_.begin() + matches, best_inlier_.begin());
    }
  }
  if (best_inliers < 2)
    return Surf1dError::kOk;
  last_model_ = true;

  // Circular mean of the inliers' displacement, unwrapped around the first inlier's.
  double reference = 0.0;
  bool have_reference = false;
  double sum = 0.0;
  for (int m = 0; m < matches; ++m) {
    if (!best_inlier_[static_cast<std::size_t>(m)])
      continue;
    const double d = Wrap(xt(m) - xs(m), nd);
    if (!have_reference) {
      reference = d;
      have_reference = true;
    }
    sum += reference + Wrap(d - reference, nd);
    result->ransac_score +=
        1.0 / static_cast<double>(
                  std::max(pairs_[static_cast<std::size_t>(m)].distance, options_.min_distance));
  }
  const double mean = Wrap(sum / best_inliers, nd);
  result->model_found = true;
  result->inliers = best_inliers;
  result->scale = best_scale;
  result->displacement = best_displacement;
  double degrees = mean * 360.0 / nd;
  if (degrees >= 180.0)
    degrees -= 360.0;
  result->heading_offset_deg = degrees;
  return Surf1dError::kOk;
}

LandmarkMatcher::MatchedPair LandmarkMatcher::last_pair(int i) const {
  if (i < 0 || i >= last_pairs_)
    return {};
  const Pair& p = pairs_[static_cast<std::size_t>(i)];
  return {static_cast<int>(p.x_stored), static_cast<int>(p.x_test), p.distance,
          last_model_ && best_inlier_[static_cast<std::size_t>(i)] != 0};
}

}  // namespace skyloc::dsp
