// dsp::HeadingEstimator: a strip circularly shifted by k columns reads as a robot turned by
// -k columns' worth of degrees (its content turned by +k), within one sample, by both
// ways; the sign and wrap are checked against hand-computed values, not the code's own
// conversion. SummariseHeadingErrors against a hand-ranked list.
#include "skyloc/dsp/heading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "skyloc/dsp/place_metrics.h"
#include "skyloc/platform/alloc_counter.h"

namespace skyloc::dsp {
namespace {

// A skyline with blobs of many widths plus grey-level texture, rounded to bytes as the
// route stores strips; column j of the shifted strip is column j - k of the original.
std::vector<float> Skyline(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(40.0, 200.0);
  std::uniform_int_distribution<int> width(2, 30);
  std::vector<float> s(static_cast<std::size_t>(n));
  int j = 0;
  while (j < n) {
    const int w = width(rng);
    const double v = level(rng);
    for (int i = 0; i < w && j < n; ++i, ++j)
      s[static_cast<std::size_t>(j)] = static_cast<float>(std::lround(v + 5 * std::sin(j * 0.7)));
  }
  return s;
}

std::vector<float> Shifted(const std::vector<float>& s, int k) {
  const int n = static_cast<int>(s.size());
  std::vector<float> out(s.size());
  for (int j = 0; j < n; ++j)
    out[static_cast<std::size_t>(j)] = s[static_cast<std::size_t>(((j - k) % n + n) % n)];
  return out;
}

TEST(Heading, ACircularShiftIsTheHeadingWithinOneSample) {
  constexpr int kN = 360;
  HeadingOptions both;
  both.surf_every_frame = true;  // (a) too, though (b) is certain on a pure shift
  HeadingEstimator estimator;
  ASSERT_EQ(estimator.Init(kN, both), HeadingError::kOk);
  const std::vector<float> stored = Skyline(kN, 3);
  // Content turned by +k columns (1 degree each): the robot turned by -k degrees,
  // wrapped into [-180, 180): k = 300 -> +60, k = 180 -> -180.
  const struct {
    int k;
    double heading_deg;
  } kCases[] = {{0, 0}, {1, -1}, {37, -37}, {180, -180}, {300, 60}, {359, 1}};
  for (const auto& c : kCases) {
    HeadingEstimate e;
    ASSERT_EQ(estimator.Estimate(stored, Shifted(stored, c.k), &e), HeadingError::kOk);
    ASSERT_TRUE(e.has_correlation) << c.k;
    // Differences across the wrap (-180 vs +179.9) are one sample apart, not 360.
    EXPECT_LE(std::fabs(WrapDegrees(e.correlation_deg - c.heading_deg)), 1.0) << c.k;
    EXPECT_GT(e.confidence, 0.99f) << c.k;
    ASSERT_TRUE(e.has_surf) << c.k;
    EXPECT_LE(std::fabs(WrapDegrees(e.surf_deg - c.heading_deg)), 1.0) << c.k;
    EXPECT_GE(e.surf_inliers, 10) << c.k;
  }
  // Fewer columns: one sample is 2 degrees.
  HeadingEstimator coarse;
  ASSERT_EQ(coarse.Init(180, both), HeadingError::kOk);
  const std::vector<float> s180 = Skyline(180, 5);
  HeadingEstimate e;
  ASSERT_EQ(coarse.Estimate(s180, Shifted(s180, 20), &e), HeadingError::kOk);
  EXPECT_LE(std::fabs(e.correlation_deg - (-40.0)), 2.0);
  EXPECT_LE(std::fabs(e.surf_deg - (-40.0)), 2.0);
}

TEST(Heading, ErrorsAndNoAllocation) {
  HeadingEstimator estimator;
  EXPECT_EQ(estimator.Init(100, HeadingOptions{}), HeadingError::kBadOptions);  // < 148 for SURF
  HeadingOptions no_surf;
  no_surf.surf = false;
  ASSERT_EQ(estimator.Init(100, no_surf), HeadingError::kOk);  // correlation needs no filter
  const std::vector<float> a = Skyline(100, 1), flat(100, 7.0f), shorter(99, 1.0f);
  HeadingEstimate e;
  EXPECT_EQ(estimator.Estimate(a, shorter, &e), HeadingError::kSizeMismatch);
  ASSERT_EQ(estimator.Estimate(a, flat, &e), HeadingError::kOk);
  EXPECT_FALSE(e.has_correlation);  // a flat strip has no turn to read
  EXPECT_FALSE(e.has_surf);

  ASSERT_EQ(estimator.Init(360, HeadingOptions{}), HeadingError::kOk);
  const std::vector<float> stored = Skyline(360, 9), test = Shifted(stored, 45);
  // A RANSAC line with fewer inliers than asked for gives no (a) heading; (b) still answers.
  HeadingOptions strict;
  strict.surf_every_frame = true;
  strict.min_surf_inliers = 4000;
  HeadingEstimator gated;
  ASSERT_EQ(gated.Init(360, strict), HeadingError::kOk);
  ASSERT_EQ(gated.Estimate(stored, test, &e), HeadingError::kOk);
  EXPECT_TRUE(e.has_correlation);
  EXPECT_FALSE(e.has_surf);
  strict.min_surf_inliers = 1;
  EXPECT_EQ(gated.Init(360, strict), HeadingError::kBadOptions);
  HeadingOptions every_frame;
  every_frame.surf_every_frame = true;  // (a) too: its path must allocate nothing either
  HeadingEstimator both;
  ASSERT_EQ(both.Init(360, every_frame), HeadingError::kOk);
  // The route frame held, and a new one every frame (the spectrum and features computed
  // again in the buffers Init sized).
  const std::vector<float> other = Skyline(360, 10);
  AllocationScope scope;
  for (int i = 0; i < 10; ++i) {
    (void)estimator.Estimate(stored, test, &e);
    (void)both.Estimate(stored, test, &e);
  }
  for (int i = 0; i < 10; ++i) {
    (void)estimator.Estimate(i % 2 == 0 ? stored : other, test, &e);
    (void)both.Estimate(i % 2 == 0 ? stored : other, test, &e);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_TRUE(e.surf_ran);
}

// (a) runs only where (b) is uncertain; the answer stays (b)'s. A pure shift of
// a textured skyline stands far out of chance: (b) answers alone. Four identical buildings
// (a period of 90 columns) give four equal peaks: uncertain, so (a) runs.
TEST(Heading, SurfRunsOnlyWhereTheCorrelationIsUncertain) {
  constexpr int kN = 360;
  HeadingEstimator estimator;
  ASSERT_EQ(estimator.Init(kN, HeadingOptions{}), HeadingError::kOk);
  const std::vector<float> stored = Skyline(kN, 3);
  HeadingEstimate e;
  ASSERT_EQ(estimator.Estimate(stored, Shifted(stored, 37), &e), HeadingError::kOk);
  EXPECT_FALSE(e.uncertain);
  EXPECT_FALSE(e.surf_ran);
  EXPECT_FALSE(e.has_surf);
  ASSERT_TRUE(e.has_heading);
  EXPECT_EQ(e.heading_deg, e.correlation_deg);
  EXPECT_LE(std::fabs(WrapDegrees(e.heading_deg - (-37.0))), 1.0);

  std::vector<float> periodic(kN);
  const std::vector<float> building = Skyline(90, 11);
  for (int j = 0; j < kN; ++j)
    periodic[static_cast<std::size_t>(j)] = building[static_cast<std::size_t>(j % 90)];
  ASSERT_EQ(estimator.Estimate(periodic, Shifted(periodic, 20), &e), HeadingError::kOk);
  EXPECT_TRUE(e.uncertain);
  EXPECT_TRUE(e.surf_ran);
  ASSERT_TRUE(e.has_heading);
  EXPECT_EQ(e.heading_deg, e.correlation_deg);  // (a) is the second opinion only

  // surf = false: never (a), whatever (b) says.
  HeadingOptions no_surf;
  no_surf.surf = false;
  ASSERT_EQ(estimator.Init(kN, no_surf), HeadingError::kOk);
  ASSERT_EQ(estimator.Estimate(periodic, Shifted(periodic, 20), &e), HeadingError::kOk);
  EXPECT_TRUE(e.uncertain);
  EXPECT_FALSE(e.surf_ran);
  EXPECT_EQ(e.heading_deg, e.correlation_deg);
}

// The estimator keeps the stored strip's features while the same strip comes again; any
// change to it, even in the same buffer and in one column, is a new strip. Every answer
// equals a fresh estimator's on the same pair (the reference: nothing held).
TEST(Heading, HeldStoredFeaturesGiveAFreshEstimatorsAnswers) {
  constexpr int kN = 360;
  HeadingOptions every_frame;
  every_frame.surf_every_frame = true;
  every_frame.min_surf_inliers = 2;
  HeadingEstimator held;
  ASSERT_EQ(held.Init(kN, every_frame), HeadingError::kOk);
  std::vector<float> stored = Skyline(kN, 21);
  const std::vector<float> other = Skyline(kN, 22);
  int compared = 0, with_surf = 0;
  const auto expect_fresh = [&](const std::vector<float>& a, const std::vector<float>& b) {
    HeadingEstimator fresh;
    ASSERT_EQ(fresh.Init(kN, every_frame), HeadingError::kOk);
    HeadingEstimate got, want;
    ASSERT_EQ(held.Estimate(a, b, &got), HeadingError::kOk);
    ASSERT_EQ(fresh.Estimate(a, b, &want), HeadingError::kOk);
    EXPECT_EQ(got.has_surf, want.has_surf) << compared;
    EXPECT_EQ(got.surf_deg, want.surf_deg) << compared;
    EXPECT_EQ(got.surf_inliers, want.surf_inliers) << compared;
    EXPECT_EQ(got.heading_deg, want.heading_deg) << compared;
    // The held stored spectrum too.
    EXPECT_EQ(got.noise, want.noise) << compared;
    EXPECT_EQ(got.runner_up, want.runner_up) << compared;
    EXPECT_EQ(got.uncertain, want.uncertain) << compared;
    ++compared;
    with_surf += want.has_surf ? 1 : 0;
  };
  expect_fresh(stored, Shifted(stored, 30));
  expect_fresh(stored, Shifted(stored, -50));  // same stored strip: features held
  expect_fresh(other, Shifted(other, 10));     // another route frame
  expect_fresh(stored, Shifted(stored, 75));   // back to the first
  // The held strip changed in place: its features must be found again.
  const std::vector<float> query = Shifted(stored, 75);
  for (int j = 100; j < 160; ++j)
    stored[static_cast<std::size_t>(j)] = 255.0f - stored[static_cast<std::size_t>(j)];
  expect_fresh(stored, query);
  stored[200] += 1.0f;
  expect_fresh(stored, query);
  EXPECT_GE(with_surf, 4);
}

TEST(Heading, WrapDegrees) {
  EXPECT_DOUBLE_EQ(WrapDegrees(180), -180);
  EXPECT_DOUBLE_EQ(WrapDegrees(-180), -180);
  EXPECT_DOUBLE_EQ(WrapDegrees(190), -170);
  EXPECT_DOUBLE_EQ(WrapDegrees(-190), 170);
  EXPECT_DOUBLE_EQ(WrapDegrees(725), 5);
}

TEST(Heading, SummaryRanksAbsoluteErrors) {
  // |errors| sorted: 0.5 1 1 2 3 4 5 6 8 40. Nearest rank: median = 5th = 3,
  // p90 = 9th = 8, max 40.
  std::vector<double> errors = {-1, 3, 0.5, -40, 2, 8, -4, 5, 6, 1};
  const HeadingErrorSummary s = SummariseHeadingErrors(errors, 12);
  EXPECT_EQ(s.frames, 12);
  EXPECT_EQ(s.estimated, 10);
  EXPECT_DOUBLE_EQ(s.median_deg, 3);
  EXPECT_DOUBLE_EQ(s.p90_deg, 8);
  EXPECT_DOUBLE_EQ(s.max_deg, 40);
  std::vector<double> none;
  EXPECT_EQ(SummariseHeadingErrors(none, 4).estimated, 0);
}

}  // namespace
}  // namespace skyloc::dsp
