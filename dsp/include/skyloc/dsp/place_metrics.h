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
#include <vector>

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

// A recorded camera position, metres, in one fixed frame per pair of runs.
struct Position3 {
  double x = 0, y = 0, z = 0;
};

double PositionDistance(const Position3& a, const Position3& b);

// ---- Ground truth and correctness: the one rule for eval, replay/demo and experiments ----
//
// A query's truth is the interval of reference frames tied for nearest to it: every frame
// within kTruthTieM of the nearest distance, contiguous with the nearest frame. A robot
// that stopped while teaching left many frames at one place; any of them is the truth.
// Ties elsewhere on the route (a loop's closing frame on its first) are another visit and
// stay out of the interval, as the nearest frame alone did before.

// 1 cm: a stop's frames are bit-identical in simulation but a recorded pose (odometry,
// RTK GNSS) wanders by about a centimetre while standing, and frames.csv rounds; yet 1 cm
// is 5x below the finest frame step in use (the ants' 5 cm), so frames of a moving robot
// tie only when the query lies halfway between two of them, where either is right.
inline constexpr double kTruthTieM = 0.01;

struct TruthInterval {
  int first = -1;    // -1: no ground truth (the query is off the reference route)
  int last = -1;     // inclusive
  int nearest = -1;  // the first reference at the smallest distance (plots)
  bool has_truth() const { return first >= 0; }
};

// The truth of a ground-truth file: one reference frame, or none for -1.
inline TruthInterval TruthAtFrame(int reference) {
  return reference >= 0 ? TruthInterval{reference, reference, reference} : TruthInterval{};
}

// truth[q] for every query: the tied interval, or none when even the nearest reference is
// farther than max_distance_m (off the route; pass infinity for no limit). A position with
// a NaN coordinate (a frame without a pose) is never near anything. O(queries x
// references). truth.size() must equal query.size().
void GroundTruthFromPositions(std::span<const Position3> reference,
                              std::span<const Position3> query, double max_distance_m,
                              std::span<TruthInterval> truth);

// How a match is judged: within +-frames of the truth interval (the paper: 5), or, with
// metres > 0, recorded within that distance of the query (the interval then only says
// whether the query has a truth at all).
// loop_frames > 0: the reference is one lap of a closed route of that many frames, so its
// last frame is next to its first and frame distances wrap around (frames mode).
struct MatchTolerance {
  int frames = 5;
  double metres = 0;
  int loop_frames = 0;
};

// `reference` and `query` are needed in distance mode only (pass {} and any position with
// a ground-truth file, which has frames only).
bool MatchIsCorrect(int matched, const TruthInterval& truth, const MatchTolerance& tolerance,
                    std::span<const Position3> reference, const Position3& query);

// The precision-recall curve of the evaluated matches, from the strictest threshold to the
// loosest, and its summary: the one precision-recall computation of the session's report,
// `skyloc eval` and the experiments. Offline (after a run): it allocates the curve.
struct PrecisionRecall {
  std::vector<PrPoint> curve;
  PrSummary summary;
};

PrecisionRecall EvaluatePrecisionRecall(std::span<const EvaluatedMatch> matches);

// ---- Heading error: eval and the heading experiment --------------------------

struct HeadingErrorSummary {
  int frames = 0;     // frames the heading was asked for (correctly matched ones)
  int estimated = 0;  // of which the method gave a heading
  // Over the estimated frames' absolute errors, degrees; the percentile is the nearest
  // rank: the smallest error that at least that share of frames stay within.
  double median_deg = 0, p90_deg = 0, max_deg = 0;
};

// Summarises signed errors (estimate - truth, degrees, already wrapped to [-180, 180));
// `errors_deg` is overwritten with the sorted absolute errors (no allocation).
HeadingErrorSummary SummariseHeadingErrors(std::span<double> errors_deg, int frames);

// ---- ROC of a recognition score (the 1D SURF paper's Fig. 4 and Table 1) ----------------
//
// Pairs of images with a score (higher = more alike) and whether they truly match. At
// threshold t every pair with score >= t is called a match: true positive rate = called
// matches among the matching pairs, false positive rate = called matches among the others.
// One point per distinct score (ties are called together), from (0, 0) at +infinity to
// (1, 1). The area under it by the trapezoid rule equals the Mann-Whitney statistic: the
// chance that a random matching pair scores above a random non-matching one, ties counting
// one half.

struct ScoredPair {
  double score = 0;
  bool match = false;
};

struct RocPoint {
  double threshold = 0;  // call pairs with score >= threshold a match
  double false_positive_rate = 0;
  double true_positive_rate = 0;
};

// Fills `curve` (needs pairs.size() + 1 points) and returns the number of points written;
// 0 when there is not at least one pair of each kind. `order` is scratch of pairs.size()
// indices. Allocates nothing.
std::size_t RocCurve(std::span<const ScoredPair> pairs, std::span<std::size_t> order,
                     std::span<RocPoint> curve);

// The trapezoid area under a curve from RocCurve (0 for an empty curve).
double RocArea(std::span<const RocPoint> curve);

}  // namespace skyloc::dsp
