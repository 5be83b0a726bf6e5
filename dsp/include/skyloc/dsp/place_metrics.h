// Place-recognition metrics: precision-recall by sweeping the acceptance threshold on the
// SeqSLAM uniqueness ratio (lower = more distinctive), as the paper's Figs. 5b, 8d, 9d.
// Definitions (docs/SEQSLAM.md, "Evaluation"):
//  - Only query frames for which the engine produced a match are evaluated.
//  - At threshold u, a match is accepted when its uniqueness <= u.
//  - Accepted and correct: true positive. Accepted and wrong (or the query has no ground
//    truth: it is off the route): false positive. Not accepted although the query has a
//    ground truth: false negative. (SeqSLAM's convention: accepting everything is 100 %
//    recall; "precision at 100 % recall" is the fraction of all matches that are right.)
//  - precision = TP / (TP + FP) (1 when nothing is accepted), recall = TP / (TP + FN).
//  - The curve has one point per distinct uniqueness value (ties are accepted together),
//    from the strictest threshold to the loosest.
//  - Area under the curve: the step sum over the points of (recall_i - recall_{i-1}) *
//    precision_i from recall 0 (no interpolation: the "average precision" estimator).
//  - Recall at 100 % precision: the largest recall of a point with no false positive (0
//    when even the most distinctive match is wrong).
#pragma once

#include <cstddef>
#include <span>

namespace skyloc::dsp {

struct EvaluatedMatch {
  float uniqueness = 1.0f;       // the engine's uniqueness ratio
  bool has_ground_truth = true;  // false: the query is not on the reference route
  bool correct = false;          // the matched reference is within tolerance of the truth
};

struct PrPoint {
  float threshold = 0.0f;  // accept uniqueness <= threshold
  double precision = 1.0;
  double recall = 0.0;
  int true_positives = 0;
  int false_positives = 0;
  int false_negatives = 0;
};

struct PrSummary {
  int evaluated = 0;                      // matches given
  int with_ground_truth = 0;              // of which have a ground truth
  int correct = 0;                        // of which are correct
  double precision_at_full_recall = 0.0;  // everything accepted
  double recall_at_full_precision = 0.0;
  double area_under_curve = 0.0;
};

// A match is correct when |matched - truth| <= tolerance (the paper: 5 frames).
inline bool MatchWithinFrames(int matched, int truth, int tolerance_frames) {
  const int d = matched - truth;
  return truth >= 0 && (d < 0 ? -d : d) <= tolerance_frames;
}

// A recorded camera position, metres, in one fixed frame per pair of runs.
struct Position3 {
  double x = 0, y = 0, z = 0;
};

double PositionDistance(const Position3& a, const Position3& b);

// Ground truth from poses: truth[q] = the reference recorded nearest to query q, or -1 when
// even that one is farther than max_distance_m (off the route; pass infinity for no limit).
// O(queries x references). truth.size() must equal query.size().
void GroundTruthFromPositions(std::span<const Position3> reference,
                              std::span<const Position3> query, double max_distance_m,
                              std::span<int> truth);

// Fills `curve` (needs matches.size() points at most) from the strictest threshold to the
// loosest and returns the number of points written. `order` is scratch of matches.size()
// indices. Allocates nothing.
std::size_t PrecisionRecallCurve(std::span<const EvaluatedMatch> matches,
                                 std::span<std::size_t> order, std::span<PrPoint> curve);

PrSummary SummarisePrecisionRecall(std::span<const EvaluatedMatch> matches,
                                   std::span<const PrPoint> curve);

}  // namespace skyloc::dsp
