// SeqSLAM engines against hand-computed values, against each other (batch with a trailing
// window = streaming, bit for bit) and against planted routes.
#include "skyloc/dsp/seqslam.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "skyloc/platform/alloc_counter.h"

namespace skyloc::dsp {
namespace {

constexpr float kTol = 1e-5f;

// The 6x6 difference matrix of a perfect route: query q matches reference q (difference
// 0), every other pair differs by 1. Stored query-major: d[q * 6 + r].
std::vector<float> DiagonalDifferences() {
  std::vector<float> d(36, 1.0f);
  for (int q = 0; q < 6; ++q)
    d[static_cast<std::size_t>(q * 6 + q)] = 0.0f;
  return d;
}

// Hand computation, R = 2 (rows r-1..r+1), N = 6, so m = 3 and the shift is
// (3 - 1) / sqrt(3) = 1.154701.
//  - Window of 3 rows holding the 0: values {0, 1, 1}, mean 2/3, sample variance
//    ((2/3)^2 + 2 (1/3)^2) / 2 = 1/3, std 0.577350. The 0 gives z = -(2/3) / 0.577350 =
//    -1.154701 -> 0.0 after the shift; a 1 gives z = (1/3) / 0.577350 = 0.577350 -> 1.732051.
//  - Window of 2 rows (r = 0 or 5) holding the 0: {0, 1}, mean 1/2, variance 1/2, std
//    0.707107: the 0 -> -0.707107 + 1.154701 = 0.447594; the 1 -> 1.861808.
//  - Window without the 0: all ones, std 0 -> z = 0 -> 1.154701.
constexpr float kShift = 1.1547005f;
constexpr float kZeroIn3 = 0.0f;
constexpr float kOneIn3 = 1.7320508f;
constexpr float kZeroIn2 = 0.4475937f;
constexpr float kOneIn2 = 1.8618080f;

TEST(SeqSlamEnhancement, HandComputedColumns) {
  const std::vector<float> d = DiagonalDifferences();
  std::vector<float> e(36);
  ASSERT_EQ(EnhanceDifferenceMatrix(d, 6, 6, 2, e), SeqSlamError::kOk);
  EXPECT_NEAR(EnhancementShift(6, 2), kShift, kTol);
  // Column 0: the 0 at row 0 (window rows 0..1), row 1's window 0..2 holds it, rest flat.
  const float col0[6] = {kZeroIn2, kOneIn3, kShift, kShift, kShift, kShift};
  // Column 2: rows 1..3 see the 0 in full windows; row 0's window (0..1) and rows 4, 5 don't.
  const float col2[6] = {kShift, kOneIn3, kZeroIn3, kOneIn3, kShift, kShift};
  // Column 5: the 0 at row 5 (window 4..5), row 4's window 3..5 holds it.
  const float col5[6] = {kShift, kShift, kShift, kShift, kOneIn3, kZeroIn2};
  for (int r = 0; r < 6; ++r) {
    EXPECT_NEAR(e[static_cast<std::size_t>(0 * 6 + r)], col0[r], kTol) << "row " << r;
    EXPECT_NEAR(e[static_cast<std::size_t>(2 * 6 + r)], col2[r], kTol) << "row " << r;
    EXPECT_NEAR(e[static_cast<std::size_t>(5 * 6 + r)], col5[r], kTol) << "row " << r;
  }
  // Row 0 of column 1: window rows 0..1 = {1, 0}: the 1 in a 2-window.
  EXPECT_NEAR(e[1 * 6 + 0], kOneIn2, kTol);
}

TEST(SeqSlamSearch, HandComputedCentredAndTrailing) {
  const std::vector<float> d = DiagonalDifferences();
  SeqSlamParams p;
  p.sequence_length = 3;
  p.v_min = 1.0f;
  p.v_max = 1.0f;
  p.uniqueness_window = 2;  // excludes starts best-1 .. best+1
  p.contrast_window = 2;

  // Centred, query t = 2: columns 1, 2, 3; trajectories start at s = 0..3 (s + 2 <= 5):
  //  s=0: e[1][0] + e[2][1] + e[3][2] = 1.861808 + 1.732051 + 1.732051 = 5.325910
  //  s=1: e[1][1] + e[2][2] + e[3][3] = 0 + 0 + 0                       = 0
  //  s=2: e[1][2] + e[2][3] + e[3][4] = 3 * 1.732051                    = 5.196152
  //  s=3: e[1][3] + e[2][4] + e[3][5] = 3 * 1.154701                    = 3.464102
  // Best s = 1, runner-up outside 0..2 is s = 3: uniqueness 0 / 3.464102 = 0.
  std::vector<float> e(36);
  ASSERT_EQ(EnhanceDifferenceMatrix(d, 6, 6, 2, e), SeqSlamError::kOk);
  TrajectorySearch search;
  ASSERT_EQ(search.Init(p), SeqSlamError::kOk);
  const float* cols[3] = {&e[6], &e[12], &e[18]};
  std::vector<float> scores(6);
  const SeqSlamMatch m = search.Search(cols, 6, 1, scores);
  EXPECT_NEAR(scores[0], 5.325910f, 1e-4f);
  EXPECT_NEAR(scores[1], 0.0f, 1e-4f);
  EXPECT_NEAR(scores[2], 5.196152f, 1e-4f);
  EXPECT_NEAR(scores[3], 3.464102f, 1e-4f);
  EXPECT_TRUE(std::isinf(scores[4]));  // would run past row 5
  EXPECT_TRUE(std::isinf(scores[5]));
  ASSERT_TRUE(m.valid);
  EXPECT_EQ(m.start, 1);
  EXPECT_EQ(m.reference, 2);  // start + floor(1.0 * position 1)
  EXPECT_NEAR(m.uniqueness, 0.0f, 1e-5f);
  EXPECT_NEAR(m.confidence, 1.0f, 1e-5f);

  // Trailing, query t = 5: columns 3, 4, 5, reported at position 2:
  //  s=0: e[3][0] + e[4][1] + e[5][2] = 3 * 1.154701             = 3.464102
  //  s=1: e[3][1] + e[4][2] + e[5][3] = 3 * 1.154701             = 3.464102
  //  s=2: e[3][2] + e[4][3] + e[5][4] = 3 * 1.732051             = 5.196152
  //  s=3: e[3][3] + e[4][4] + e[5][5] = 0 + 0 + 0.447594         = 0.447594
  // Best s = 3 (reference 5); starts 2..4 excluded, runner-up 3.464102:
  // uniqueness 0.447594 / 3.464102 = 0.129209.
  std::vector<SeqSlamMatch> matches(6);
  ASSERT_EQ(SeqSlamFromDifferences(d, 6, 6, p, SeqSlamWindow::kTrailing, matches),
            SeqSlamError::kOk);
  EXPECT_FALSE(matches[0].valid);  // t = 0, 1: fewer than 3 frames so far
  EXPECT_FALSE(matches[1].valid);
  ASSERT_TRUE(matches[5].valid);
  EXPECT_EQ(matches[5].start, 3);
  EXPECT_EQ(matches[5].reference, 5);
  EXPECT_NEAR(matches[5].score, 0.447594f, 1e-4f);
  EXPECT_NEAR(matches[5].uniqueness, 0.129209f, 1e-4f);
  for (int t = 2; t < 6; ++t) {
    ASSERT_TRUE(matches[static_cast<std::size_t>(t)].valid);
    EXPECT_EQ(matches[static_cast<std::size_t>(t)].reference, t);
  }
  // Centred: t = 0 and t = 5 have no full window (t-1 .. t+1).
  ASSERT_EQ(SeqSlamFromDifferences(d, 6, 6, p, SeqSlamWindow::kCentred, matches),
            SeqSlamError::kOk);
  EXPECT_FALSE(matches[0].valid);
  EXPECT_FALSE(matches[5].valid);
  ASSERT_TRUE(matches[2].valid);
  EXPECT_EQ(matches[2].reference, 2);
  EXPECT_NEAR(matches[2].score, 0.0f, 1e-4f);
}

TEST(SeqSlamSearch, OffsetsFollowOpenSeqSlamFloor) {
  // OpenSeqSLAM: idx_add = floor((0:ds) .* v); v = 0.8..1.2 in steps of 0.1 at ds = 10.
  SeqSlamParams p;  // defaults
  TrajectorySearch search;
  ASSERT_EQ(search.Init(p), SeqSlamError::kOk);
  ASSERT_EQ(search.velocity_count(), 5);
  EXPECT_NEAR(search.velocity(4), 1.2f, 1e-6f);
  // floor(9 * 0.9) = 8, floor(5 * 1.2) = 6, floor(9 * 1.1) = 9, floor(3 * 0.8) = 2.
  EXPECT_EQ(search.offset(1, 9), 8);
  EXPECT_EQ(search.offset(4, 5), 6);
  EXPECT_EQ(search.offset(3, 9), 9);
  EXPECT_EQ(search.offset(0, 3), 2);
  EXPECT_EQ(search.offset(2, 7), 7);
}

TEST(SeqSlamParams, Validation) {
  SeqSlamParams p;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kOk);
  p.sequence_length = 0;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadSequenceLength);
  p = SeqSlamParams{};
  p.v_max = 0.5f;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadVelocity);
  p = SeqSlamParams{};
  p.v_step = 0.0f;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadVelocity);
  p.v_step = 0.001f;  // 401 velocities
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadVelocity);
  p.v_step = 1e-30f;  // 4e29 velocities: must not overflow the count
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadVelocity);
  p = SeqSlamParams{};
  p.v_min = std::nanf("");
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadVelocity);
  p = SeqSlamParams{};
  p.contrast_window = -1;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadContrastWindow);
  p = SeqSlamParams{};
  p.uniqueness_window = -2;
  EXPECT_EQ(ValidateSeqSlamParams(p), SeqSlamError::kBadUniquenessWindow);
  StreamingSeqSlam s;
  SeqSlamMatch m;
  const float q[4] = {};
  EXPECT_EQ(s.Step(q, &m), SeqSlamError::kNotInitialised);
  EXPECT_EQ(s.Init(SeqSlamParams{}, 0, 10), SeqSlamError::kBadDimension);
  EXPECT_EQ(s.Init(SeqSlamParams{}, 4, 0), SeqSlamError::kBadCapacity);
  ASSERT_EQ(s.Init(SeqSlamParams{}, 4, 1), SeqSlamError::kOk);
  EXPECT_EQ(s.Step(q, &m), SeqSlamError::kEmptyDatabase);
  EXPECT_EQ(s.AddReference(std::span<const float>(q, 3)), SeqSlamError::kSizeMismatch);
  EXPECT_EQ(s.AddReference(q), SeqSlamError::kOk);
  EXPECT_EQ(s.AddReference(q), SeqSlamError::kDatabaseFull);
  for (int e = 0; e <= static_cast<int>(SeqSlamError::kEmptyDatabase); ++e)
    EXPECT_STRNE(SeqSlamErrorMessage(static_cast<SeqSlamError>(e)), "unknown SeqSLAM error");
}

// A route of n_ref descriptors that change smoothly along it (each element a sum of
// sinusoids of the position with random periods of 4..20 frames, as real places blend
// into their neighbours), and a query run that traverses references start, start + v,
// start + 2v, ... with Gaussian noise.
struct PlantedRoute {
  int dim = 16;
  std::vector<float> reference;
  std::vector<float> query;
  std::vector<int> truth;  // reference index under each query frame

  std::span<const float> Reference(int r) const { return Row(reference, r); }
  std::span<const float> Query(int t) const { return Row(query, t); }

 private:
  std::span<const float> Row(const std::vector<float>& rows, int i) const {
    return std::span<const float>(rows).subspan(static_cast<std::size_t>(i * dim),
                                                static_cast<std::size_t>(dim));
  }
};

// Teaches the whole route to a streaming engine.
::testing::AssertionResult AddRoute(StreamingSeqSlam& s, const PlantedRoute& route) {
  const int n = static_cast<int>(route.reference.size()) / route.dim;
  for (int r = 0; r < n; ++r) {
    if (const SeqSlamError e = s.AddReference(route.Reference(r)); e != SeqSlamError::kOk)
      return ::testing::AssertionFailure() << "reference " << r << ": " << SeqSlamErrorMessage(e);
  }
  return ::testing::AssertionSuccess();
}

PlantedRoute MakeRoute(int n_ref, int n_query, double start, double v, float noise, unsigned seed,
                       bool smooth = true) {
  PlantedRoute r;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> period(4.0, 20.0), phase(0.0, 6.283185307179586);
  std::normal_distribution<float> gauss(0.0f, noise);
  constexpr int kWaves = 3;
  std::vector<double> periods(static_cast<std::size_t>(r.dim * kWaves)),
      phases(static_cast<std::size_t>(r.dim * kWaves));
  for (std::size_t i = 0; i < periods.size(); ++i) {
    periods[i] = period(rng);
    phases[i] = phase(rng);
  }
  r.reference.resize(static_cast<std::size_t>(n_ref * r.dim));
  for (int ref = 0; ref < n_ref; ++ref) {
    for (int i = 0; i < r.dim; ++i) {
      double x = 0.0;
      for (int w = 0; w < kWaves; ++w) {
        const std::size_t k = static_cast<std::size_t>(i * kWaves + w);
        x += smooth ? std::sin(6.283185307179586 * ref / periods[k] + phases[k])
                    : std::sin(phases[k] * (ref + 1) * 1000.0);  // unrelated neighbours
      }
      r.reference[static_cast<std::size_t>(ref * r.dim + i)] = static_cast<float>(x);
    }
  }
  for (int t = 0; t < n_query; ++t) {
    const int ref = static_cast<int>(std::floor(start + v * t));
    r.truth.push_back(ref);
    for (int i = 0; i < r.dim; ++i)
      r.query.push_back(r.reference[static_cast<std::size_t>(ref * r.dim + i)] + gauss(rng));
  }
  return r;
}

TEST(SeqSlamStreaming, EqualsBatchWithTrailingWindow) {
  for (const int ds : {1, 4, 10}) {
    const PlantedRoute route = MakeRoute(200, 60, 30.0, 1.0, 0.2f, 7u + static_cast<unsigned>(ds));
    SeqSlamParams p;
    p.sequence_length = ds;
    std::vector<SeqSlamMatch> batch(60);
    ASSERT_EQ(
        BatchSeqSlam(route.reference, route.query, route.dim, p, SeqSlamWindow::kTrailing, batch),
        SeqSlamError::kOk);
    StreamingSeqSlam s;
    ASSERT_EQ(s.Init(p, route.dim, 256), SeqSlamError::kOk);
    ASSERT_TRUE(AddRoute(s, route));
    for (int t = 0; t < 60; ++t) {
      SeqSlamMatch m;
      ASSERT_EQ(s.Step(route.Query(t), &m), SeqSlamError::kOk);
      const SeqSlamMatch& b = batch[static_cast<std::size_t>(t)];
      ASSERT_EQ(m.valid, b.valid) << "ds " << ds << " t " << t;
      if (!m.valid)
        continue;
      // The same arithmetic in the same order: identical floats.
      EXPECT_EQ(m.reference, b.reference) << "ds " << ds << " t " << t;
      EXPECT_EQ(m.start, b.start);
      EXPECT_EQ(m.velocity, b.velocity);
      EXPECT_EQ(m.score, b.score);
      EXPECT_EQ(m.uniqueness, b.uniqueness);
      EXPECT_EQ(m.confidence, b.confidence);
    }
  }
}

// The streaming step works through the database a chunk of rows at a time (difference,
// enhancement and search interleaved); a route several chunks long, with contrast windows
// that straddle the chunk boundaries, must still give the batch engine's floats exactly.
TEST(SeqSlamStreaming, LongRouteEqualsBatchAcrossChunks) {
  const int n_ref = 2600, n_query = 30;
  const PlantedRoute route = MakeRoute(n_ref, n_query, 1013.0, 0.9, 0.2f, 29u);
  for (const ReferenceStorage storage : {ReferenceStorage::kFloat32, ReferenceStorage::kBFloat16}) {
    std::vector<float> reference = route.reference;
    if (storage == ReferenceStorage::kBFloat16) {
      for (float& x : reference)
        x = FromBFloat16(ToBFloat16(x));
    }
    for (const int contrast : {10, 601}) {
      SeqSlamParams p;
      p.contrast_window = contrast;
      std::vector<SeqSlamMatch> batch(n_query);
      ASSERT_EQ(BatchSeqSlam(reference, route.query, route.dim, p, SeqSlamWindow::kTrailing, batch),
                SeqSlamError::kOk);
      StreamingSeqSlam s;
      ASSERT_EQ(s.Init(p, route.dim, n_ref, storage), SeqSlamError::kOk);
      ASSERT_TRUE(AddRoute(s, route));
      int found = 0;
      for (int t = 0; t < n_query; ++t) {
        SeqSlamMatch m;
        ASSERT_EQ(s.Step(route.Query(t), &m), SeqSlamError::kOk);
        const SeqSlamMatch& b = batch[static_cast<std::size_t>(t)];
        ASSERT_EQ(m.valid, b.valid) << "t " << t;
        if (!m.valid)
          continue;
        EXPECT_EQ(m.reference, b.reference) << "R " << contrast << " t " << t;
        EXPECT_EQ(m.start, b.start);
        EXPECT_EQ(m.velocity, b.velocity);
        EXPECT_EQ(m.score, b.score);
        EXPECT_EQ(m.uniqueness, b.uniqueness);
        found += std::abs(m.reference - route.truth[static_cast<std::size_t>(t)]) <= 1;
      }
      // And it localises: the planted route is found once the window is full.
      EXPECT_GE(found, n_query - 10 - 2) << "R " << contrast;
    }
  }
}

// A streaming engine holding `route` as `storage`, stepped over its 40 queries: every match
// must equal the batch engine's on `held` (the route as that storage holds it), with
// nothing allocated. Returns how many matches are right within one frame.
int StreamingMatchesBatchOnHeldRoute(const PlantedRoute& route, const std::vector<float>& held,
                                     ReferenceStorage storage) {
  SeqSlamParams p;
  std::vector<SeqSlamMatch> batch(40);
  EXPECT_EQ(BatchSeqSlam(held, route.query, route.dim, p, SeqSlamWindow::kTrailing, batch),
            SeqSlamError::kOk);
  StreamingSeqSlam s;
  EXPECT_EQ(s.Init(p, route.dim, 150, storage), SeqSlamError::kOk);
  EXPECT_TRUE(AddRoute(s, route));
  AllocationScope scope;
  int correct = 0;
  for (int t = 0; t < 40; ++t) {
    SeqSlamMatch m;
    EXPECT_EQ(s.Step(route.Query(t), &m), SeqSlamError::kOk);
    const SeqSlamMatch& b = batch[static_cast<std::size_t>(t)];
    EXPECT_EQ(m.valid, b.valid) << "t " << t;
    EXPECT_EQ(m.reference, b.reference) << "t " << t;
    EXPECT_EQ(m.score, b.score) << "t " << t;
    EXPECT_EQ(m.uniqueness, b.uniqueness) << "t " << t;
    correct += m.valid && std::abs(m.reference - route.truth[static_cast<std::size_t>(t)]) <= 1;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  return correct;
}

TEST(SeqSlamStreaming, BFloat16StorageEqualsBatchOnRoundedDescriptors) {
  const PlantedRoute route = MakeRoute(150, 40, 20.0, 1.1, 0.3f, 17u);
  SeqSlamParams p;
  std::vector<float> rounded = route.reference;
  for (float& x : rounded)
    x = FromBFloat16(ToBFloat16(x));
  // The rounding costs nothing here.
  EXPECT_EQ(StreamingMatchesBatchOnHeldRoute(route, rounded, ReferenceStorage::kBFloat16), 31);
  EXPECT_EQ(StreamingSeqSlam::BytesPerReference(p, 120, ReferenceStorage::kBFloat16),
            2u * 120 + 4u * (10 + 2));
}

// ---- Code rows (ReferenceStorage::kCodes8, kCodes16) -----------------------------------

// The codes' contract, checked against its analytic bound (seqslam.h): for 16 bits every
// value within half a step, the step 2^e below max(row) / 32767.5; for 8 bits (square
// law) |v - c^2 2^e| <= (sqrt(v / 2^e) + 1/4) 2^e with 2^e <= max(row) / 32640; the largest
// value's code in the top of the range; decoding then encoding again gives the same codes.
template <typename Code>
void ExpectCodesWithinTheirBound(unsigned seed) {
  constexpr bool kSquareLaw = sizeof(Code) == 1;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> magnitude(-40, 40);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t dim = 1 + static_cast<std::size_t>(trial % 130);
    const float scale = std::ldexp(1.0f, magnitude(rng));
    std::vector<float> row(dim);
    for (float& v : row)
      v = unit(rng) * unit(rng) * scale;
    if (trial % 7 == 0)
      row[0] = 0.0f;
    double max = 0;
    for (const float v : row)
      max = std::max(max, static_cast<double>(v));
    std::vector<Code> codes(dim);
    const std::int8_t e = EncodeCodes<Code>(row, codes);
    std::vector<float> decoded(dim);
    DecodeCodes<Code>(codes, e, decoded);
    const double step = std::ldexp(1.0, e);
    ASSERT_LE(step, max / (kSquareLaw ? 32640.0 : 32767.5) + 1e-30) << "trial " << trial;
    Code top = 0;
    for (std::size_t i = 0; i < dim; ++i) {
      const double v = static_cast<double>(row[i]), c = static_cast<double>(codes[i]);
      const double bound = kSquareLaw ? (std::sqrt(v / step) + 0.25) * step : step / 2;
      EXPECT_LE(std::fabs(v - static_cast<double>(decoded[i])), bound) << trial << " " << i;
      EXPECT_EQ(static_cast<double>(decoded[i]), (kSquareLaw ? c * c : c) * step);
      top = std::max(top, codes[i]);
    }
    if (max > 0) {
      EXPECT_GE(top, kSquareLaw ? 181 : 32768) << "trial " << trial;
    }
    std::vector<Code> again(dim);
    EXPECT_EQ(EncodeCodes<Code>(decoded, again), e) << "trial " << trial;
    EXPECT_EQ(again, codes) << "trial " << trial;
  }
}

TEST(ReferenceCodes, EveryValueWithinTheCodesBound) {
  ExpectCodesWithinTheirBound<std::uint8_t>(5u);
  ExpectCodesWithinTheirBound<std::uint16_t>(6u);
}

TEST(ReferenceCodes, WorkedExamples) {
  // 8 bits, square law. max 1 = 0.5 * 2^1: 2^e = 2^-15, so 1 -> sqrt(32768) = 181.02 -> 181,
  // 0.5 -> sqrt(16384) = 128, 0.25 -> sqrt(8192) = 90.5 -> 91 (above the tie).
  std::vector<std::uint8_t> codes(4);
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{1.0f, 0.5f, 0.25f, 0.0f}, codes), -15);
  EXPECT_EQ(codes, (std::vector<std::uint8_t>{181, 128, 91, 0}));
  // 255^2 fits 2^e = 1; 65281 >= 255.5^2 does not, so the step doubles: sqrt(32640.5) ->
  // 181.
  std::vector<std::uint8_t> one(1);
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{65025.0f}, one), 0);
  EXPECT_EQ(one[0], 255);
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{65281.0f}, one), 1);
  EXPECT_EQ(one[0], 181);
  // Ties go to even: sqrt(180.5^2) -> 180, sqrt(5.5^2) -> 6.
  std::vector<std::uint8_t> ties(3);
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{65025.0f, 32580.25f, 30.25f}, ties), 0);
  EXPECT_EQ(ties, (std::vector<std::uint8_t>{255, 180, 6}));
  // Negative and NaN values are not amplitudes: code 0; an all-zero row stays zero.
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{-1.0f, std::nanf(""), 2.0f}, ties), -14);
  EXPECT_EQ(ties, (std::vector<std::uint8_t>{0, 0, 181}));
  EXPECT_EQ(EncodeCodes<std::uint8_t>(std::vector<float>{0.0f, 0.0f, 0.0f}, ties),
            kCodeMinExponent);
  EXPECT_EQ(ties, (std::vector<std::uint8_t>{0, 0, 0}));
  // 16 bits, linear: max 1 -> 2^-15, so 1 -> 32768 and 2^-16 + 2^-17 (1.5 steps) -> 2.
  std::vector<std::uint16_t> wide(2);
  EXPECT_EQ(EncodeCodes<std::uint16_t>(std::vector<float>{1.0f, 0x1p-15f + 0x1p-16f}, wide), -15);
  EXPECT_EQ(wide, (std::vector<std::uint16_t>{32768, 2}));
}

// The code scan gives DifferenceColumn's floats over the decoded rows, bit for bit, at
// every descriptor length (whole lanes and tails).
TEST(ReferenceCodes, DifferenceColumnEqualsTheDecodedFloats) {
  std::mt19937 rng(9u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const int dim : {1, 7, 8, 13, 64, 120}) {
    const int n = 37;
    std::vector<float> rows(static_cast<std::size_t>(n * dim)),
        query(static_cast<std::size_t>(dim));
    for (float& v : rows)
      v = unit(rng) * unit(rng);
    for (float& v : query)
      v = unit(rng) * 0.5f;
    std::vector<std::uint8_t> codes8(rows.size());
    std::vector<std::uint16_t> codes16(rows.size());
    std::vector<std::int8_t> e8(static_cast<std::size_t>(n)), e16(static_cast<std::size_t>(n));
    std::vector<float> decoded8(rows.size()), decoded16(rows.size());
    const auto d = static_cast<std::size_t>(dim);
    for (std::size_t r = 0; r < static_cast<std::size_t>(n); ++r) {
      const std::span<const float> row(rows.data() + r * d, d);
      e8[r] = EncodeCodes<std::uint8_t>(row, std::span(codes8.data() + r * d, d));
      e16[r] = EncodeCodes<std::uint16_t>(row, std::span(codes16.data() + r * d, d));
      DecodeCodes<std::uint8_t>(std::span<const std::uint8_t>(codes8.data() + r * d, d), e8[r],
                                std::span(decoded8.data() + r * d, d));
      DecodeCodes<std::uint16_t>(std::span<const std::uint16_t>(codes16.data() + r * d, d), e16[r],
                                 std::span(decoded16.data() + r * d, d));
    }
    std::vector<float> want(static_cast<std::size_t>(n)), got(static_cast<std::size_t>(n));
    DifferenceColumn(decoded8, dim, query, want);
    DifferenceColumnCodes<std::uint8_t>(codes8, e8, dim, query, got);
    EXPECT_EQ(got, want) << "8-bit codes, dim " << dim;
    DifferenceColumn(decoded16, dim, query, want);
    DifferenceColumnCodes<std::uint16_t>(codes16, e16, dim, query, got);
    EXPECT_EQ(got, want) << "16-bit codes, dim " << dim;
    // And the decoded column is within the codes' bound of the exact one: the mean of the
    // per-element bounds (square law, seqslam.h).
    std::vector<float> exact(static_cast<std::size_t>(n));
    DifferenceColumn(rows, dim, query, exact);
    DifferenceColumnCodes<std::uint8_t>(codes8, e8, dim, query, got);
    for (std::size_t r = 0; r < static_cast<std::size_t>(n); ++r) {
      const double step = std::ldexp(1.0, e8[r]);
      double half_step = 0;  // the mean bound
      for (std::size_t i = 0; i < d; ++i)
        half_step += (std::sqrt(static_cast<double>(rows[r * d + i]) / step) + 0.25) * step;
      half_step /= static_cast<double>(d);
      EXPECT_LE(std::fabs(static_cast<double>(got[r]) - static_cast<double>(exact[r])),
                half_step + 1e-6)
          << dim;
    }
  }
}

TEST(SeqSlamStreaming, CodeStorageEqualsBatchOnDecodedDescriptors) {
  PlantedRoute route = MakeRoute(150, 40, 20.0, 1.1, 0.3f, 17u);
  // Amplitudes are >= 0: the planted sines (|x| <= 3) moved up.
  for (float& x : route.reference)
    x += 3.0f;
  for (float& x : route.query)
    x += 3.0f;
  for (const ReferenceStorage storage : {ReferenceStorage::kCodes8, ReferenceStorage::kCodes16}) {
    std::vector<float> decoded = route.reference;
    const auto d = static_cast<std::size_t>(route.dim);
    for (std::size_t r = 0; r < 150; ++r) {
      const std::span<float> row(decoded.data() + r * d, d);
      if (storage == ReferenceStorage::kCodes8) {
        std::vector<std::uint8_t> c(d);
        DecodeCodes<std::uint8_t>(c, EncodeCodes<std::uint8_t>(row, c), row);
      } else {
        std::vector<std::uint16_t> c(d);
        DecodeCodes<std::uint16_t>(c, EncodeCodes<std::uint16_t>(row, c), row);
      }
    }
    EXPECT_EQ(StreamingMatchesBatchOnHeldRoute(route, decoded, storage), 31)
        << ReferenceStorageName(storage);  // as float32 and bfloat16
  }
  EXPECT_EQ(StreamingSeqSlam::BytesPerReference(SeqSlamParams{}, 64, ReferenceStorage::kCodes8),
            64u + 1 + 4u * (10 + 2));
  EXPECT_EQ(ReferenceRowBytes(ReferenceStorage::kCodes16, 120), 241u);
}

TEST(SeqSlamStreaming, BFloat16RoundsToNearestEven) {
  EXPECT_EQ(ToBFloat16(1.0f), 0x3F80);
  EXPECT_EQ(ToBFloat16(-2.0f), 0xC000);
  // 1 + 2^-8 lies halfway between 1 and 1 + 2^-7: ties go to the even mantissa (1).
  EXPECT_EQ(ToBFloat16(1.0f + 0x1p-8f), 0x3F80);
  // 1 + 3 * 2^-8 lies halfway between 1 + 2^-7 (odd) and 1 + 2^-6 (even): rounds up.
  EXPECT_EQ(ToBFloat16(1.0f + 3 * 0x1p-8f), 0x3F82);
  EXPECT_EQ(ToBFloat16(1.0f + 0x1p-8f + 0x1p-12f), 0x3F81);  // above halfway
  EXPECT_EQ(FromBFloat16(0x3F81), 1.0f + 0x1p-7f);
  EXPECT_TRUE(std::isnan(FromBFloat16(ToBFloat16(std::nanf("")))));
  EXPECT_TRUE(std::isinf(FromBFloat16(ToBFloat16(std::numeric_limits<float>::infinity()))));
}

TEST(SeqSlamStreaming, SingleImageModeMatchesEveryFrame) {
  // Unrelated neighbouring references: single frames are distinctive on their own.
  const PlantedRoute route = MakeRoute(100, 30, 10.0, 1.0, 0.05f, 3u, /*smooth=*/false);
  SeqSlamParams p;
  p.sequence_length = 1;
  StreamingSeqSlam s;
  ASSERT_EQ(s.Init(p, route.dim, 100), SeqSlamError::kOk);
  ASSERT_TRUE(AddRoute(s, route));
  for (int t = 0; t < 30; ++t) {
    SeqSlamMatch m;
    ASSERT_EQ(s.Step(route.Query(t), &m), SeqSlamError::kOk);
    ASSERT_TRUE(m.valid) << "t " << t;  // no warm-up with ds = 1
    EXPECT_EQ(m.reference, route.truth[static_cast<std::size_t>(t)]);
    EXPECT_GE(m.confidence, 0.0f);
    EXPECT_LE(m.confidence, 1.0f);
  }
}

TEST(SeqSlamBatch, PlantedRouteFoundAtEveryVelocity) {
  // Noise as large as the signal: single frames are often wrong (checked below), the
  // sequence has to do the work.
  for (const double v : {0.8, 0.9, 1.0, 1.1, 1.2}) {
    const PlantedRoute route = MakeRoute(400, 80, 100.0, v, 1.0f, 11u);
    SeqSlamParams p;  // defaults: ds 10, v 0.8..1.2
    for (const SeqSlamWindow w : {SeqSlamWindow::kCentred, SeqSlamWindow::kTrailing}) {
      std::vector<SeqSlamMatch> matches(80);
      ASSERT_EQ(BatchSeqSlam(route.reference, route.query, route.dim, p, w, matches),
                SeqSlamError::kOk);
      int valid = 0;
      double velocity_sum = 0.0;
      for (int t = 0; t < 80; ++t) {
        const SeqSlamMatch& m = matches[static_cast<std::size_t>(t)];
        if (!m.valid)
          continue;
        ++valid;
        // floor(start + v t) and start' + floor(v j) may differ by one frame.
        EXPECT_NEAR(m.reference, route.truth[static_cast<std::size_t>(t)], 1)
            << "v " << v << " t " << t;
        velocity_sum += static_cast<double>(m.velocity);
      }
      EXPECT_EQ(valid, 80 - 9);  // ds - 1 frames lack a full window
      // Single velocities may be off by a step where the floor patterns tie; on average
      // the search recovers the planted one.
      EXPECT_NEAR(velocity_sum / valid, v, 0.05) << "v " << v;
    }
    // The same data frame by frame (ds = 1) is wrong often: the test is not trivial.
    SeqSlamParams single;
    single.sequence_length = 1;
    std::vector<SeqSlamMatch> matches(80);
    ASSERT_EQ(BatchSeqSlam(route.reference, route.query, route.dim, single,
                           SeqSlamWindow::kTrailing, matches),
              SeqSlamError::kOk);
    int wrong = 0;
    for (int t = 0; t < 80; ++t) {
      wrong += std::abs(matches[static_cast<std::size_t>(t)].reference -
                        route.truth[static_cast<std::size_t>(t)]) > 1
                   ? 1
                   : 0;
    }
    EXPECT_GT(wrong, 10) << "v " << v;
  }
}

// A second implementation, written straight from OpenSeqSLAM's MATLAB text with the
// differences documented in seqslam.h: each window's mean and std recomputed from scratch
// in double (no running sums), every trajectory summed in double, no blocking.
std::vector<SeqSlamMatch> NaiveSeqSlam(const std::vector<float>& d, int n, int m,
                                       const SeqSlamParams& p, SeqSlamWindow window) {
  const int h = p.contrast_window / 2;
  const int mm = std::min(n, 2 * h + 1);
  const double shift = mm > 1 ? (mm - 1) / std::sqrt(static_cast<double>(mm)) : 0.0;
  auto at = [&](int q, int r) {
    return static_cast<double>(d[static_cast<std::size_t>(q * n + r)]);
  };
  std::vector<double> e(static_cast<std::size_t>(n * m));
  for (int q = 0; q < m; ++q) {
    for (int i = 0; i < n; ++i) {
      const int a = std::max(0, i - h), b = std::min(n - 1, i + h), k = b - a + 1;
      double mu = 0, sq = 0;
      for (int r = a; r <= b; ++r) {
        mu += at(q, r);
        sq += at(q, r) * at(q, r);
      }
      mu /= k;
      double var = 0;
      for (int r = a; r <= b; ++r)
        var += (at(q, r) - mu) * (at(q, r) - mu);
      var = k > 1 ? var / (k - 1) : 0.0;
      const double z = var > 1e-10 * sq / k ? (at(q, i) - mu) / std::sqrt(var) : 0.0;
      e[static_cast<std::size_t>(q * n + i)] = z + shift;
    }
  }
  std::vector<double> v;
  for (int k = 0;; ++k) {
    const double vk = static_cast<double>(p.v_min) + k * static_cast<double>(p.v_step);
    if (vk > static_cast<double>(p.v_max) + 1e-6)
      break;
    v.push_back(vk);
  }
  const int ds = p.sequence_length;
  auto off = [&](std::size_t k, int j) { return static_cast<int>(std::floor(j * v[k] + 1e-9)); };
  std::vector<SeqSlamMatch> out(static_cast<std::size_t>(m));
  for (int t = 0; t < m; ++t) {
    const int first = window == SeqSlamWindow::kCentred ? t - ds / 2 : t - ds + 1;
    if (first < 0 || first + ds > m)
      continue;
    std::vector<double> score(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
    std::vector<std::size_t> best_k(static_cast<std::size_t>(n), 0);
    for (int s = 0; s < n; ++s) {
      for (std::size_t k = 0; k < v.size(); ++k) {
        if (s + off(k, ds - 1) >= n)
          continue;
        double sum = 0;
        for (int j = 0; j < ds; ++j)
          sum += e[static_cast<std::size_t>((first + j) * n + s + off(k, j))];
        if (sum < score[static_cast<std::size_t>(s)]) {
          score[static_cast<std::size_t>(s)] = sum;
          best_k[static_cast<std::size_t>(s)] = k;
        }
      }
    }
    const auto best = std::min_element(score.begin(), score.end());
    if (std::isinf(*best))
      continue;
    const int bs = static_cast<int>(best - score.begin());
    double second = std::numeric_limits<double>::infinity();
    for (int s = 0; s < n; ++s) {
      if (std::abs(s - bs) > p.uniqueness_window / 2)
        second = std::min(second, score[static_cast<std::size_t>(s)]);
    }
    SeqSlamMatch& r = out[static_cast<std::size_t>(t)];
    r.valid = true;
    r.start = bs;
    r.reference = bs + off(best_k[static_cast<std::size_t>(bs)], t - first);
    r.score = static_cast<float>(*best);
    r.uniqueness = std::isinf(second) || second <= 0 ? 1.0f : static_cast<float>(*best / second);
  }
  return out;
}

TEST(SeqSlamBatch, MatchesNaiveReference) {
  // Random differences with a planted diagonal at 0.9 frames per frame and a flat band
  // (zero std), both windows, several sequence lengths.
  const int n = 90, m = 40;
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::vector<float> d(static_cast<std::size_t>(n * m));
  for (int q = 0; q < m; ++q) {
    for (int r = 0; r < n; ++r) {
      float x = uni(rng);
      if (r == 10 + (q * 9) / 10)
        x *= 0.3f;
      if (r >= 40 && r < 52)
        x = 0.5f;
      d[static_cast<std::size_t>(q * n + r)] = x;
    }
  }
  for (const int ds : {1, 4, 10, 11}) {
    for (const SeqSlamWindow w : {SeqSlamWindow::kCentred, SeqSlamWindow::kTrailing}) {
      SeqSlamParams p;
      p.sequence_length = ds;
      std::vector<SeqSlamMatch> fast(static_cast<std::size_t>(m));
      ASSERT_EQ(SeqSlamFromDifferences(d, n, m, p, w, fast), SeqSlamError::kOk);
      const std::vector<SeqSlamMatch> slow = NaiveSeqSlam(d, n, m, p, w);
      for (int t = 0; t < m; ++t) {
        const SeqSlamMatch& a = fast[static_cast<std::size_t>(t)];
        const SeqSlamMatch& b = slow[static_cast<std::size_t>(t)];
        ASSERT_EQ(a.valid, b.valid) << "ds " << ds << " t " << t;
        if (!a.valid)
          continue;
        EXPECT_EQ(a.start, b.start) << "ds " << ds << " t " << t;
        EXPECT_EQ(a.reference, b.reference) << "ds " << ds << " t " << t;
        EXPECT_NEAR(a.score, b.score, 1e-4f * std::max(1.0f, b.score));
        EXPECT_NEAR(a.uniqueness, b.uniqueness, 1e-4f);
      }
    }
  }
}

TEST(SeqSlamEnhancement, ZeroVarianceGivesFiniteOutput) {
  // A constant column (all references equally far) and a database of identical frames.
  std::vector<float> d(50, 3.0f), out(50);
  EnhanceColumn(d, 10, out);
  for (float x : out)
    EXPECT_FLOAT_EQ(x, EnhancementShift(50, 10));
  std::vector<float> same(20 * 8, 0.5f), query(8, 0.5f);
  SeqSlamParams p;
  p.sequence_length = 3;
  StreamingSeqSlam s;
  ASSERT_EQ(s.Init(p, 8, 20), SeqSlamError::kOk);
  for (int r = 0; r < 20; ++r)
    ASSERT_EQ(
        s.AddReference(std::span<const float>(same).subspan(static_cast<std::size_t>(r * 8), 8)),
        SeqSlamError::kOk);
  for (int t = 0; t < 5; ++t) {
    SeqSlamMatch m;
    ASSERT_EQ(s.Step(query, &m), SeqSlamError::kOk);
    if (t < 2) {
      EXPECT_FALSE(m.valid);
      continue;
    }
    ASSERT_TRUE(m.valid);
    EXPECT_TRUE(std::isfinite(m.score));
    EXPECT_EQ(m.uniqueness, 1.0f);  // every place looks the same: not distinctive
    EXPECT_EQ(m.confidence, 0.0f);
  }
  // A tiny database: one reference, no runner-up.
  StreamingSeqSlam one;
  ASSERT_EQ(one.Init(SeqSlamParams{.sequence_length = 1}, 8, 1), SeqSlamError::kOk);
  ASSERT_EQ(one.AddReference(query), SeqSlamError::kOk);
  SeqSlamMatch m;
  ASSERT_EQ(one.Step(query, &m), SeqSlamError::kOk);
  ASSERT_TRUE(m.valid);
  EXPECT_EQ(m.reference, 0);
  EXPECT_TRUE(std::isfinite(m.score));
  EXPECT_EQ(m.uniqueness, 1.0f);
}

// The enhancement fed a column in arbitrary pieces writes only rows whose windows are
// complete, and ends with exactly EnhanceColumn's floats.
TEST(SeqSlamEnhancement, IncrementalEqualsWholeColumn) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> uni(0.0f, 2.0f);
  std::uniform_int_distribution<int> piece(1, 700);
  const int n = 1500;
  std::vector<float> d(n);
  for (float& x : d)
    x = uni(rng);
  std::fill(d.begin() + 300, d.begin() + 340, 1.0f);  // a flat stretch (zero std)
  for (const int contrast : {0, 1, 2, 10, 37, 5000}) {
    std::vector<float> whole(n), pieces(n, -1.0f);
    EnhanceColumn(d, contrast, whole);
    ColumnEnhancer enhancer;
    enhancer.Begin(n, contrast);
    int available = 0, done = 0;
    while (done < n) {
      available = std::min(n, available + piece(rng));
      const int now = enhancer.Advance(d.data(), available, pieces.data());
      ASSERT_GE(now, done);
      if (available < n) {  // a row needs the R/2 rows after it (and one more to slide on)
        ASSERT_LE(now, std::max(0, available - contrast / 2 - 1)) << "R " << contrast;
      }
      for (int r = done; r < now; ++r)
        ASSERT_EQ(pieces[static_cast<std::size_t>(r)], whole[static_cast<std::size_t>(r)])
            << "R " << contrast << " row " << r;
      for (int r = now; r < n; ++r)  // nothing written ahead of the rows it reports
        ASSERT_EQ(pieces[static_cast<std::size_t>(r)], -1.0f) << "R " << contrast << " row " << r;
      done = now;
    }
    for (float x : whole)
      ASSERT_TRUE(std::isfinite(x));
  }
}

TEST(SeqSlamStreaming, DatabaseShorterThanTrajectoryGivesNoMatch) {
  SeqSlamParams p;  // ds 10 at v >= 0.8 needs >= 8 references
  StreamingSeqSlam s;
  ASSERT_EQ(s.Init(p, 2, 5), SeqSlamError::kOk);
  const float x[2] = {0.0f, 1.0f};
  for (int r = 0; r < 5; ++r)
    ASSERT_EQ(s.AddReference(x), SeqSlamError::kOk);
  for (int t = 0; t < 12; ++t) {
    SeqSlamMatch m;
    ASSERT_EQ(s.Step(x, &m), SeqSlamError::kOk);
    EXPECT_FALSE(m.valid);
  }
}

TEST(SeqSlamStreaming, StepAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  const PlantedRoute route = MakeRoute(300, 40, 20.0, 1.0, 0.2f, 5u);
  SeqSlamParams p;
  StreamingSeqSlam s;
  ASSERT_EQ(s.Init(p, route.dim, 300), SeqSlamError::kOk);
  ASSERT_TRUE(AddRoute(s, route));
  AllocationScope scope;
  int valid = 0;
  for (int t = 0; t < 40; ++t) {
    SeqSlamMatch m;
    const SeqSlamError e = s.Step(route.Query(t), &m);
    valid += e == SeqSlamError::kOk && m.valid ? 1 : 0;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(valid, 31);
  EXPECT_EQ(StreamingSeqSlam::BytesPerReference(p, 120), 4u * (120 + 10 + 2));
  EXPECT_GE(s.AllocatedBytes(), 300u * StreamingSeqSlam::BytesPerReference(p, 16));
}

}  // namespace
}  // namespace skyloc::dsp
