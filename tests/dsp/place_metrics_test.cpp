#include "skyloc/dsp/place_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace skyloc::dsp {
namespace {

TEST(PlaceMetrics, HandComputedCurve) {
  // uniqueness, has ground truth, correct:
  //   A 0.1 yes right | B 0.2 yes wrong | C 0.3 yes right | D 0.3 off-route | E 0.5 yes right
  // 4 queries have a ground truth (A, B, C, E).
  //   u <= 0.1: TP 1 FP 0, FN 3 (B C E)   P 1     R 1/4
  //   u <= 0.2: TP 1 FP 1, FN 2 (C E)     P 1/2   R 1/3
  //   u <= 0.3: TP 2 FP 2 (B D), FN 1 (E) P 1/2   R 2/3   (C and D tie: one point)
  //   u <= 0.5: TP 3 FP 2, FN 0           P 3/5   R 1
  // AUC = 1/4 * 1 + (1/3 - 1/4) * 1/2 + (2/3 - 1/3) * 1/2 + (1 - 2/3) * 3/5 = 0.658333
  const std::vector<EvaluatedMatch> m = {{0.3f, true, true},
                                         {0.1f, true, true},
                                         {0.5f, true, true},
                                         {0.2f, true, false},
                                         {0.3f, false, false}};
  std::vector<std::size_t> order(m.size());
  std::vector<PrPoint> curve(m.size());
  const std::size_t n = PrecisionRecallCurve(m, order, curve);
  ASSERT_EQ(n, 4u);
  const double p[4] = {1.0, 0.5, 0.5, 0.6}, r[4] = {0.25, 1.0 / 3, 2.0 / 3, 1.0};
  const float u[4] = {0.1f, 0.2f, 0.3f, 0.5f};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(curve[i].threshold, u[i]);
    EXPECT_NEAR(curve[i].precision, p[i], 1e-12) << i;
    EXPECT_NEAR(curve[i].recall, r[i], 1e-12) << i;
  }
  EXPECT_EQ(curve[2].false_positives, 2);
  EXPECT_EQ(curve[2].false_negatives, 1);
  const PrSummary s = SummarisePrecisionRecall(m, std::span<const PrPoint>(curve.data(), n));
  EXPECT_EQ(s.evaluated, 5);
  EXPECT_EQ(s.with_ground_truth, 4);
  EXPECT_EQ(s.correct, 3);
  EXPECT_NEAR(s.precision_at_full_recall, 0.6, 1e-12);
  EXPECT_NEAR(s.recall_at_full_precision, 0.25, 1e-12);
  EXPECT_NEAR(s.area_under_curve, 0.25 + (1.0 / 12) / 2 + (1.0 / 3) / 2 + (1.0 / 3) * 0.6, 1e-12);
}

TEST(PlaceMetrics, PerfectAndHopelessRuns) {
  const std::vector<EvaluatedMatch> perfect = {{0.2f, true, true}, {0.4f, true, true}};
  std::vector<std::size_t> order(2);
  std::vector<PrPoint> curve(2);
  std::size_t n = PrecisionRecallCurve(perfect, order, curve);
  PrSummary s = SummarisePrecisionRecall(perfect, std::span<const PrPoint>(curve.data(), n));
  EXPECT_DOUBLE_EQ(s.precision_at_full_recall, 1.0);
  EXPECT_DOUBLE_EQ(s.recall_at_full_precision, 1.0);
  EXPECT_DOUBLE_EQ(s.area_under_curve, 1.0);
  const std::vector<EvaluatedMatch> hopeless = {{0.2f, true, false}, {0.4f, true, false}};
  n = PrecisionRecallCurve(hopeless, order, curve);
  s = SummarisePrecisionRecall(hopeless, std::span<const PrPoint>(curve.data(), n));
  EXPECT_DOUBLE_EQ(s.precision_at_full_recall, 0.0);
  EXPECT_DOUBLE_EQ(s.recall_at_full_precision, 0.0);
  EXPECT_DOUBLE_EQ(s.area_under_curve, 0.0);
  EXPECT_EQ(PrecisionRecallCurve({}, order, curve), 0u);
}

TEST(PlaceMetrics, FrameTolerance) {
  EXPECT_TRUE(MatchWithinFrames(15, 10, 5));
  EXPECT_TRUE(MatchWithinFrames(5, 10, 5));
  EXPECT_FALSE(MatchWithinFrames(16, 10, 5));
  EXPECT_FALSE(MatchWithinFrames(3, 10, 5));
  EXPECT_FALSE(MatchWithinFrames(0, -1, 5));  // no ground truth
}

TEST(PlaceMetrics, GroundTruthFromPositions) {
  // Reference route along x at 1 m spacing; queries 0.4 m to the side.
  const std::vector<Position3> ref = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  const std::vector<Position3> query = {
      {2.2, 0.4, 0},  // nearest reference 2 (0.447 m)
      {0.9, 0.4, 0},  // nearest 1 (0.412 m)
      {3.0, 5.0, 0},  // nearest 3 but 5 m away: off the route with a 1 m tolerance
      {1.5, 0.0, 0},  // exactly between 1 and 2: the first
  };
  std::vector<int> truth(4);
  GroundTruthFromPositions(ref, query, 1.0, truth);
  EXPECT_EQ(truth, (std::vector<int>{2, 1, -1, 1}));
  GroundTruthFromPositions(ref, query, std::numeric_limits<double>::infinity(), truth);
  EXPECT_EQ(truth[2], 3);
  EXPECT_DOUBLE_EQ(PositionDistance({0, 0, 0}, {2, 3, 6}), 7.0);
}

}  // namespace
}  // namespace skyloc::dsp
