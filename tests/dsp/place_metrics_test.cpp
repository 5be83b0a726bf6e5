#include "skyloc/dsp/place_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <span>
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
  const PrecisionRecall pr = EvaluatePrecisionRecall(m);
  const std::vector<PrPoint>& curve = pr.curve;
  ASSERT_EQ(curve.size(), 4u);
  const double p[4] = {1.0, 0.5, 0.5, 0.6}, r[4] = {0.25, 1.0 / 3, 2.0 / 3, 1.0};
  const float u[4] = {0.1f, 0.2f, 0.3f, 0.5f};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(curve[i].threshold, u[i]);
    EXPECT_NEAR(curve[i].precision, p[i], 1e-12) << i;
    EXPECT_NEAR(curve[i].recall, r[i], 1e-12) << i;
  }
  EXPECT_EQ(curve[2].false_positives, 2);
  EXPECT_EQ(curve[2].false_negatives, 1);
  const PrSummary& s = pr.summary;
  EXPECT_EQ(s.evaluated, 5);
  EXPECT_EQ(s.with_ground_truth, 4);
  EXPECT_EQ(s.correct, 3);
  EXPECT_NEAR(s.precision_at_full_recall, 0.6, 1e-12);
  EXPECT_NEAR(s.recall_at_full_precision, 0.25, 1e-12);
  EXPECT_NEAR(s.area_under_curve, 0.25 + (1.0 / 12) / 2 + (1.0 / 3) / 2 + (1.0 / 3) * 0.6, 1e-12);
}

TEST(PlaceMetrics, PerfectAndHopelessRuns) {
  const std::vector<EvaluatedMatch> perfect = {{0.2f, true, true}, {0.4f, true, true}};
  PrSummary s = EvaluatePrecisionRecall(perfect).summary;
  EXPECT_DOUBLE_EQ(s.precision_at_full_recall, 1.0);
  EXPECT_DOUBLE_EQ(s.recall_at_full_precision, 1.0);
  EXPECT_DOUBLE_EQ(s.area_under_curve, 1.0);
  const std::vector<EvaluatedMatch> hopeless = {{0.2f, true, false}, {0.4f, true, false}};
  s = EvaluatePrecisionRecall(hopeless).summary;
  EXPECT_DOUBLE_EQ(s.precision_at_full_recall, 0.0);
  EXPECT_DOUBLE_EQ(s.recall_at_full_precision, 0.0);
  EXPECT_DOUBLE_EQ(s.area_under_curve, 0.0);
  const PrecisionRecall none = EvaluatePrecisionRecall({});
  EXPECT_TRUE(none.curve.empty());
  EXPECT_EQ(none.summary.evaluated, 0);
  EXPECT_DOUBLE_EQ(none.summary.area_under_curve, 0.0);
}

// A reference run along x at 1 m steps that stops at x = 3 for five frames (3..7).
const std::vector<Position3> kStopRoute = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0},
                                           {3, 0, 0}, {3, 0, 0}, {3, 0, 0}, {3, 0, 0},
                                           {4, 0, 0}, {5, 0, 0}, {6, 0, 0}, {7, 0, 0}};
constexpr double kNoLimit = std::numeric_limits<double>::infinity();

TruthInterval TruthOf(const std::vector<Position3>& reference, Position3 query,
                      double max_distance_m = kNoLimit) {
  TruthInterval truth[1];
  GroundTruthFromPositions(reference, std::span<const Position3>(&query, 1), max_distance_m, truth);
  return truth[0];
}

void ExpectInterval(const TruthInterval& t, int first, int last, int nearest) {
  EXPECT_EQ(t.first, first);
  EXPECT_EQ(t.last, last);
  EXPECT_EQ(t.nearest, nearest);
}

TEST(PlaceMetrics, AStopIsOneTruthInterval) {
  // 0.2 m beside the stop: frames 3..7 are all 0.2 m away.
  const TruthInterval t = TruthOf(kStopRoute, {3, 0.2, 0});
  ExpectInterval(t, 3, 7, 3);
  const MatchTolerance two_frames{2, 0};
  // Within 2 frames of 3..7: 1..9. (The nearest frame alone, 3, would call 6..9 wrong.)
  for (int matched = 0; matched < 12; ++matched) {
    EXPECT_EQ(MatchIsCorrect(matched, t, two_frames, {}, {}), matched >= 1 && matched <= 9)
        << "matched " << matched;
  }
}

TEST(PlaceMetrics, NearTiesWithinOneCentimetreJoinTheInterval) {
  // Between frames 1 and 2: 0.504 m and 0.496 m, 8 mm apart: both are the truth.
  ExpectInterval(TruthOf(kStopRoute, {1.504, 0, 0}), 1, 2, 2);
  // 0.52 m and 0.48 m, 4 cm apart: frame 2 alone.
  ExpectInterval(TruthOf(kStopRoute, {1.52, 0, 0}), 2, 2, 2);
  // Exactly between: the first is the nearest, both are the truth.
  ExpectInterval(TruthOf(kStopRoute, {1.5, 0, 0}), 1, 2, 1);
}

TEST(PlaceMetrics, AQueryOffTheRouteHasNoTruth) {
  const TruthInterval off = TruthOf(kStopRoute, {3, 5, 0}, 1.0);  // 5 m from the stop
  EXPECT_FALSE(off.has_truth());
  ExpectInterval(off, -1, -1, -1);
  EXPECT_FALSE(MatchIsCorrect(3, off, MatchTolerance{5, 0}, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(3, off, MatchTolerance{0, 10.0}, kStopRoute, {3, 5, 0}));
  // Without a limit the same query belongs to the stop.
  ExpectInterval(TruthOf(kStopRoute, {3, 5, 0}), 3, 7, 3);
  // At exactly the limit it is still on the route (<=).
  EXPECT_TRUE(TruthOf(kStopRoute, {3, 1, 0}, 1.0).has_truth());
}

TEST(PlaceMetrics, DistanceModeJudgesTheMatchedPosition) {
  const TruthInterval t = TruthOf(kStopRoute, {3, 0.2, 0});
  const MatchTolerance metres{0, 1.5};
  // Frame 8 is at (4, 0): sqrt(1 + 0.04) = 1.02 m from the query; frame 9 at 2.01 m.
  EXPECT_TRUE(MatchIsCorrect(8, t, metres, kStopRoute, {3, 0.2, 0}));
  EXPECT_FALSE(MatchIsCorrect(9, t, metres, kStopRoute, {3, 0.2, 0}));
  EXPECT_TRUE(MatchIsCorrect(2, t, metres, kStopRoute, {3, 0.2, 0}));  // 1.02 m
  EXPECT_FALSE(MatchIsCorrect(0, t, metres, kStopRoute, {3, 0.2, 0}));
  EXPECT_FALSE(MatchIsCorrect(-1, t, metres, kStopRoute, {3, 0.2, 0}));  // no match
  EXPECT_FALSE(MatchIsCorrect(12, t, metres, kStopRoute, {3, 0.2, 0}));  // not a frame
}

TEST(PlaceMetrics, TiesElsewhereOnTheRouteAreAnotherVisit) {
  // A loop back to its start: frames 0 and 4 share a place; the query is at frame 0's.
  const std::vector<Position3> loop = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}};
  ExpectInterval(TruthOf(loop, {0, 0.1, 0}), 0, 0, 0);
}

TEST(PlaceMetrics, PositionsWithoutAPoseAreNeverNear) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Position3> ref = {{nan, nan, nan}, {2, 0, 0}, {nan, 0, 0}};
  ExpectInterval(TruthOf(ref, {0, 0, 0}), 1, 1, 1);
  EXPECT_FALSE(MatchIsCorrect(0, TruthOf(ref, {0, 0, 0}), MatchTolerance{0, 5.0}, ref, {0, 0, 0}));
  EXPECT_FALSE(TruthOf(std::vector<Position3>{{nan, 0, 0}}, {0, 0, 0}).has_truth());
  EXPECT_FALSE(TruthOf({}, {0, 0, 0}).has_truth());
}

TEST(PlaceMetrics, AGroundTruthFileGivesOneFrame) {
  EXPECT_FALSE(TruthAtFrame(-1).has_truth());
  const TruthInterval t = TruthAtFrame(10);
  ExpectInterval(t, 10, 10, 10);
  EXPECT_TRUE(MatchIsCorrect(15, t, MatchTolerance{5, 0}, {}, {}));
  EXPECT_TRUE(MatchIsCorrect(5, t, MatchTolerance{5, 0}, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(16, t, MatchTolerance{5, 0}, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(4, t, MatchTolerance{5, 0}, {}, {}));
  EXPECT_DOUBLE_EQ(PositionDistance({0, 0, 0}, {2, 3, 6}), 7.0);
}

// A reference that is one lap of a closed route: its last frames are next to its first.
TEST(PlaceMetrics, AClosedLoopWrapsFrameDistances) {
  const MatchTolerance open{5, 0};
  const MatchTolerance loop{5, 0, 100};
  EXPECT_FALSE(MatchIsCorrect(99, TruthAtFrame(0), open, {}, {}));
  EXPECT_TRUE(MatchIsCorrect(99, TruthAtFrame(0), loop, {}, {}));
  EXPECT_TRUE(MatchIsCorrect(95, TruthAtFrame(0), loop, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(94, TruthAtFrame(0), loop, {}, {}));
  EXPECT_TRUE(MatchIsCorrect(2, TruthAtFrame(97), loop, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(3, TruthAtFrame(97), loop, {}, {}));
  EXPECT_FALSE(MatchIsCorrect(50, TruthAtFrame(0), loop, {}, {}));
}

// The ROC area against its independent definition: the Mann-Whitney statistic counted pair
// by pair (a matching pair above a non-matching one scores 1, a tie 1/2), on random score
// sets with many ties (integer scores 0..9) and without (continuous scores).
TEST(RocCurve, AreaEqualsTheMannWhitneyStatisticCountedPairByPair) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 40; ++trial) {
    const bool ties = trial % 2 == 0;
    std::uniform_int_distribution<int> digit(0, 9);
    std::uniform_real_distribution<double> real(0.0, 1.0);
    std::vector<ScoredPair> pairs(static_cast<std::size_t>(5 + trial * 7));
    for (ScoredPair& p : pairs) {
      p.match = real(rng) < 0.3;
      // Matches score higher on average, so the area is away from 1/2.
      p.score = (ties ? digit(rng) : real(rng) * 10.0) + (p.match ? 2.0 : 0.0);
    }
    pairs[0].match = true;
    pairs[1].match = false;
    double u = 0;
    int positives = 0, negatives = 0;
    for (const ScoredPair& a : pairs) {
      (a.match ? positives : negatives) += 1;
      for (const ScoredPair& b : pairs)
        if (a.match && !b.match)
          u += a.score > b.score ? 1.0 : a.score == b.score ? 0.5 : 0.0;
    }
    std::vector<std::size_t> order(pairs.size());
    std::vector<RocPoint> curve(pairs.size() + 1);
    const std::size_t n = RocCurve(pairs, order, curve);
    ASSERT_GE(n, 2u);
    EXPECT_NEAR(RocArea(std::span(curve).first(n)), u / (positives * negatives), 1e-12)
        << "trial " << trial;
    EXPECT_EQ(curve[0].false_positive_rate, 0.0);
    EXPECT_EQ(curve[n - 1].false_positive_rate, 1.0);
    EXPECT_EQ(curve[n - 1].true_positive_rate, 1.0);
  }
}

// By hand: scores 5 (match), 4 (no), 4 (match), 2 (no). Points: (0,0), (0,1/2) at 5,
// (1/2,1) at 4 (the tie called together), (1,1) at 2. Area = 1/2 * 3/4 + 1/2 * 1 = 7/8.
TEST(RocCurve, HandComputedCurveAndDegenerateInput) {
  const std::vector<ScoredPair> pairs = {{4, false}, {5, true}, {2, false}, {4, true}};
  std::vector<std::size_t> order(4);
  std::vector<RocPoint> curve(5);
  ASSERT_EQ(RocCurve(pairs, order, curve), 4u);
  EXPECT_EQ(curve[1].threshold, 5.0);
  EXPECT_EQ(curve[1].true_positive_rate, 0.5);
  EXPECT_EQ(curve[2].false_positive_rate, 0.5);
  EXPECT_EQ(curve[2].true_positive_rate, 1.0);
  EXPECT_DOUBLE_EQ(RocArea(std::span(curve).first(4)), 7.0 / 8.0);
  const std::vector<ScoredPair> only_matches = {{1, true}, {2, true}};
  EXPECT_EQ(RocCurve(only_matches, order, curve), 0u);
  EXPECT_EQ(RocCurve(pairs, std::span(order).first(3), curve), 0u);  // scratch too small
}

}  // namespace
}  // namespace skyloc::dsp
