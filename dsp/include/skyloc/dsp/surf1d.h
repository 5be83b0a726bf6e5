// 1D SURF (Anderson, Yusmanthia, Hengst, Sowmya 2012): scale-invariant blob features of a
// circular 1-D signal (the horizon strip, horizon_strip.h), and their matching between a
// stored and a test strip with the nearest-neighbour ratio test and RANSAC on the line
// model x_test = b_s * x_stored + b_d. See docs/SURF1D.md.
//
// Detection. The 1-D Hessian is the second derivative, approximated like SURF's D_xx by a
// box filter of three lobes of l columns each, weights +1, -2, +1 (filter size L = 3 l),
// read from the integral of the signal in four look-ups. On a quadratic signal
// D = l^3 f'' exactly, and on smooth signals D / l^3 equals the second derivative of a
// Gaussian of sigma^2 = l^2 / 4 - 1 / 12 (sigma ~ l / 2) to fourth order in frequency.
// The response is D / l ~ 4 sigma^2 f'', the scale-normalised second derivative (a
// Gaussian blob of width sigma_b responds most at sigma = sqrt(2) sigma_b, l ~ 2.8
// sigma_b); on a step edge of contrast C its largest value is C. Filter sizes follow SURF's
// octaves: octave o (0-based), interval i: l = 2^(o+1) (i + 1) + 1, so 4 octaves x 3 intervals give
// l = 3 5 7 | 5 9 13 | 9 17 25 | 17 33 49. SURF repeats sizes across octaves because it subsamples
// each octave; we evaluate every layer at every column (the signal is short), so repeated sizes
// would be identical layers and are kept once: the layers are the distinct l, ascending (9 for the
// paper's parameters). A feature is a column whose |response| is above the threshold and a local
// maximum of |response| along the strip at its layer (the paper's relaxed test), or optionally also
// across the neighbouring layers (SURF's 3 x 3 test, 3 x 3 in 1-D: position x scale).
// Positions are whole columns (the paper drops SURF's sub-pixel interpolation).
// Everything wraps around: the strip is 360 degrees, so shifting the strip by k columns
// shifts every feature by k (mod n) and leaves its descriptor unchanged.
//
// Descriptor (6-D, SURF's with 3 sub-regions instead of 4 x 4 and one axis): with step
// s = max(1, round(0.4 l)), 15 samples at columns x + k s, k = -7..7, each the Haar
// response (sum of [p, p + s) minus sum of [p - s, p)) weighted by a Gaussian of 2.5
// samples; sub-region r = (k + 7) / 5 contributes (sum dx, sum |dx|). The vector is
// scaled to unit length (contrast invariance; a flat region gives all zeros). The sign of
// the Laplacian (+1: dark blob, f'' > 0; -1: bright blob) rejects candidates in matching.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace skyloc::dsp {

struct Surf1dOptions {
  int octaves = 4;
  int intervals = 3;
  // Minimum |response| (strip units: a step edge of contrast C responds with up to C).
  float threshold = 2.0f;
  // false: maximum along the strip at its own layer (the paper). true: also greater than
  // the neighbouring layers (SURF's scale-space test; fewer, better-localised features).
  bool suppress_across_scale = false;

  bool operator==(const Surf1dOptions&) const = default;
};

inline constexpr int kSurf1dDescriptorSize = 6;

struct Surf1dFeature {
  std::int32_t position = 0;       // column, 0..n-1
  std::int32_t lobe = 0;           // l: the box filter's lobe width in columns (filter 3 l)
  std::int32_t layer = 0;          // index into Surf1d::lobes()
  float response = 0.0f;           // signed D / l
  std::int8_t laplacian_sign = 0;  // +1 dark blob, -1 bright blob
  std::array<float, kSurf1dDescriptorSize> descriptor{};
};

enum class Surf1dError : std::uint8_t {
  kOk,
  kBadOptions,       // octaves outside 1..8, intervals outside 1..8, threshold < 0 or NaN
  kStripTooShort,    // the strip is shorter than the largest filter + 1
  kNotInitialised,   // Detect/Match before a successful Init
  kSizeMismatch,     // the strip is not the length given to Init
  kTooManyFeatures,  // more features than the matcher was sized for
  kBadFeature,       // a feature's laplacian_sign is not +1 or -1 (not from Detect)
};

const char* Surf1dErrorMessage(Surf1dError error);

// Largest lobe width for these options (the strip must be longer than 3 x this).
int Surf1dMaxLobe(const Surf1dOptions& options);

class Surf1d {
 public:
  // Sizes the integral and the response layers for strips of n columns. Not for the
  // frame path.
  Surf1dError Init(int n, const Surf1dOptions& options);

  // Detects features of `strip` into `features` (caller-owned), sorted by position then
  // layer; *count is how many were written. When there are more candidates than
  // features.size(), the strongest |response| are kept and dropped() counts the rest.
  // Allocates nothing.
  Surf1dError Detect(std::span<const float> strip, std::span<Surf1dFeature> features, int* count);

  int n() const { return n_; }
  // Distinct lobe widths, ascending: layer i uses lobes()[i].
  std::span<const int> lobes() const { return lobes_; }
  // Signed response D / l of the last Detect at (layer, position).
  float Response(int layer, int position) const {
    return responses_[static_cast<std::size_t>(layer) * static_cast<std::size_t>(n_) +
                      static_cast<std::size_t>(position)];
  }
  int dropped() const { return dropped_; }

 private:
  // Sum of the circular signal over columns [a, b), -pad_ <= a <= b <= n + pad_.
  double BoxSum(long a, long b) const;
  // The descriptor's sample spacing for a lobe width: max(1, round(0.4 l)).
  static long DescriptorStep(int lobe);
  void Describe(int position, int layer, Surf1dFeature* feature) const;

  Surf1dOptions options_;
  int n_ = 0;
  int dropped_ = 0;
  std::vector<int> lobes_;
  std::vector<long> steps_;  // DescriptorStep of each layer's lobe
  long pad_ = 0;  // columns of wrap-around on either side: the widest filter or descriptor
  // integral_[i] = sum of the periodic strip over columns [-pad_, i - pad_).
  std::vector<double> integral_;
  std::array<double, 15> weights_{};  // descriptor Gaussian, per sample
  std::vector<float> responses_;      // layers x n
  // |response| of each layer with one wrapped column either side: layer li's column x in
  // [-1, n] at li * (n + 2) + x + 1, so the neighbour tests read no wrap-around index.
  std::vector<float> magnitudes_;
  // Detect's within-layer test for one layer, a byte a column (1: above the threshold and a
  // local maximum along the strip), zero past n up to a whole number of 8-byte words.
  std::vector<std::uint8_t> peaks_;
};

struct LandmarkMatchOptions {
  float ratio = 0.7f;          // nearest / second-nearest distance must be below this
  float min_distance = 1e-3f;  // distance floor in the 1 / distance score
  // RANSAC's lines: when the pairs give no more distinct lines (i < j) than this, every one
  // is tried once (the best line exactly); otherwise at most this many random draws.
  int ransac_iterations = 200;
  float inlier_threshold = 2.0f;  // columns
  float max_scale = 1.25f;        // b_s within [1 / max_scale, max_scale] (> 0)
  std::uint64_t seed = 1;         // the same inputs always give the same answer

  bool operator==(const LandmarkMatchOptions&) const = default;
};

struct LandmarkMatch {
  int matches = 0;           // nearest-neighbour matches passing the ratio test
  double score = 0.0;        // sum of 1 / distance over those matches (NN score)
  bool model_found = false;  // RANSAC found a line with >= 2 inliers
  int inliers = 0;
  double ransac_score = 0.0;  // sum of 1 / distance over the inliers (NN with RANSAC)
  double scale = 1.0;         // b_s
  double displacement = 0.0;  // b_d, columns, wrapped to [-n/2, n/2]
  // Circular mean of x_test - x_stored over the inliers, in degrees in [-180, 180): how
  // far the test strip's content is turned from the stored strip's, towards increasing
  // azimuth. A robot that turned by +psi about body z sees its scene turned by -psi.
  double heading_offset_deg = 0.0;
};

class LandmarkMatcher {
 public:
  // Sizes the buffers for up to max_features stored and max_features test features. Not
  // for the frame path.
  Surf1dError Init(int max_features, const LandmarkMatchOptions& options);

  // Holds the stored features for the next MatchStored calls, their descriptors split by
  // the Laplacian sign (only the same sign competes): a route frame's features are set once
  // and matched against any number of queries. Allocates nothing.
  Surf1dError SetStored(std::span<const Surf1dFeature> stored);

  // Matches test features to the held stored ones on strips of n columns: the nearest
  // neighbour of the same Laplacian sign with the ratio test, then RANSAC's line through the
  // pairs. Allocates nothing.
  Surf1dError MatchStored(std::span<const Surf1dFeature> test, int n, LandmarkMatch* result);

  // The nearest two held stored features of test's Laplacian sign, as the straightforward
  // scan over them in the stored order finds them: `best` and `second` the smallest and the
  // second smallest squared descriptor distance (duplicates counted; infinity when there
  // are fewer candidates), `index` the first stored feature at `best` (its index in
  // SetStored's span), -1 when best is infinite. Each distance is the sum over k of
  // (stored[k] - test[k])^2 in floats, added in k's order. MatchStored's search; for tests.
  struct Nearest {
    int index = -1;
    float best = 0.0f;
    float second = 0.0f;
  };
  Nearest NearestTwo(const Surf1dFeature& test) const;

  // SetStored(stored), then MatchStored(test, n, result).
  Surf1dError Match(std::span<const Surf1dFeature> stored, std::span<const Surf1dFeature> test,
                    int n, LandmarkMatch* result);

  // The last Match's pairs that passed the ratio test, with RANSAC's verdict on each
  // (inlier is false for all when no model was found): for tools that draw the matches.
  struct MatchedPair {
    int x_stored = 0;  // columns
    int x_test = 0;
    float distance = 0.0f;
    bool inlier = false;
  };
  int last_pair_count() const { return last_pairs_; }
  MatchedPair last_pair(int i) const;

 private:
  // The held stored features of one Laplacian sign, sorted by one descriptor component
  // (the key: the one whose values spread most on this side), or in the given order when a
  // component is not finite.
  struct StoredSide {
    // Dimension-major: component k of slot s at k * stride_ + s, so four consecutive slots'
    // distances are computed lane by lane (each feature's sum in its own order). Slots from
    // count to the next multiple of four hold +infinity.
    std::vector<float> descriptors;
    std::vector<std::int32_t> positions;  // columns
    std::vector<std::int32_t> indices;    // index in SetStored's span
    int count = 0;
    int key = 0;          // the key component
    bool sorted = false;  // every component finite, the slots sorted by the key
  };

  // NearestTwo on one side, `index` the slot in it. With ratio2 > 0 the search may stop
  // once best < ratio2 * second is sure however it ends: best and index are exact, second
  // is then only some value >= the true one for which best < ratio2 * second holds too.
  Nearest NearestOnSide(const StoredSide& side, const Surf1dFeature& test, float ratio2) const;

  // RANSAC's inliers of the line through anchor pair `anchor` with slope `scale`, into
  // best_inlier_: the arithmetic of the search, so the same pairs it counted.
  void MarkInliers(int anchor, double scale, int n);

  LandmarkMatchOptions options_;
  int capacity_ = 0;
  int stride_ = 0;                    // capacity_ rounded up to a multiple of four
  std::array<StoredSide, 2> stored_;  // [0]: laplacian_sign +1, [1]: -1
  // SetStored's sort, side s's from s * capacity_: the key's order bits, then the index.
  std::vector<std::uint64_t> order_;
  bool has_stored_ = false;
  // The pairs passing the ratio test: positions in columns (whole numbers, held as doubles
  // so RANSAC's residuals convert none), descriptor distance.
  std::vector<double> pair_stored_;
  std::vector<double> pair_test_;
  std::vector<float> pair_distance_;
  std::vector<std::uint8_t> best_inlier_;
  int last_pairs_ = 0;
  bool last_model_ = false;
};

}  // namespace skyloc::dsp
