#include "skyloc/dsp/place_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace skyloc::dsp {

double PositionDistance(const Position3& a, const Position3& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

void GroundTruthFromPositions(std::span<const Position3> reference,
                              std::span<const Position3> query, double max_distance_m,
                              std::span<TruthInterval> truth) {
  const std::size_t n = std::min(query.size(), truth.size());
  for (std::size_t q = 0; q < n; ++q) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_r = reference.size();
    for (std::size_t r = 0; r < reference.size(); ++r) {
      const double d = PositionDistance(query[q], reference[r]);
      if (d < best) {  // the first of equally near references
        best = d;
        best_r = r;
      }
    }
    if (best_r == reference.size() || !(best <= max_distance_m)) {
      truth[q] = TruthInterval{};
      continue;
    }
    auto tied = [&](std::size_t r) {
      return PositionDistance(query[q], reference[r]) <= best + kTruthTieM;
    };
    std::size_t first = best_r, last = best_r;
    while (first > 0 && tied(first - 1))
      --first;
    while (last + 1 < reference.size() && tied(last + 1))
      ++last;
    truth[q] = {static_cast<int>(first), static_cast<int>(last), static_cast<int>(best_r)};
  }
}

bool MatchIsCorrect(int matched, const TruthInterval& truth, const MatchTolerance& tolerance,
                    std::span<const Position3> reference, const Position3& query) {
  if (!truth.has_truth() || matched < 0)
    return false;
  if (tolerance.metres > 0) {
    return static_cast<std::size_t>(matched) < reference.size() &&
           PositionDistance(query, reference[static_cast<std::size_t>(matched)]) <=
               tolerance.metres;
  }
  if (matched >= truth.first - tolerance.frames && matched <= truth.last + tolerance.frames)
    return true;
  // Around the loop: the match one lap earlier or later.
  const int lap = tolerance.loop_frames;
  return lap > 0 && ((matched - lap >= truth.first - tolerance.frames) ||
                     (matched + lap <= truth.last + tolerance.frames));
}

namespace {

// Fills `curve` (matches.size() points at most) and returns the number of points written.
std::size_t PrecisionRecallCurve(std::span<const EvaluatedMatch> matches,
                                 std::span<std::size_t> order, std::span<PrPoint> curve) {
  const std::size_t n = std::min(matches.size(), order.size());
  std::iota(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), std::size_t{0});
  std::stable_sort(
      order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
      [&](std::size_t a, std::size_t b) { return matches[a].uniqueness < matches[b].uniqueness; });
  int positives = 0;  // queries with a ground truth: TP + FN at every threshold
  for (std::size_t i = 0; i < n; ++i)
    positives += matches[i].has_ground_truth ? 1 : 0;
  int tp = 0, fp = 0, accepted_positives = 0;
  std::size_t points = 0;
  std::size_t i = 0;
  while (i < n && points < curve.size()) {
    const float threshold = matches[order[i]].uniqueness;
    // Matches with equal uniqueness are accepted together.
    while (i < n && matches[order[i]].uniqueness == threshold) {
      const EvaluatedMatch& m = matches[order[i]];
      if (m.has_ground_truth)
        ++accepted_positives;
      if (m.has_ground_truth && m.correct) {
        ++tp;
      } else {
        ++fp;
      }
      ++i;
    }
    PrPoint p;
    p.threshold = threshold;
    p.true_positives = tp;
    p.false_positives = fp;
    p.false_negatives = positives - accepted_positives;
    p.precision = tp + fp > 0 ? static_cast<double>(tp) / (tp + fp) : 1.0;
    const int denominator = tp + p.false_negatives;
    p.recall = denominator > 0 ? static_cast<double>(tp) / denominator : 0.0;
    curve[points++] = p;
  }
  return points;
}

PrSummary SummarisePrecisionRecall(std::span<const EvaluatedMatch> matches,
                                   std::span<const PrPoint> curve) {
  PrSummary s;
  s.evaluated = static_cast<int>(matches.size());
  for (const EvaluatedMatch& m : matches) {
    s.with_ground_truth += m.has_ground_truth ? 1 : 0;
    s.correct += m.has_ground_truth && m.correct ? 1 : 0;
  }
  if (curve.empty())
    return s;
  s.precision_at_full_recall = curve.back().precision;
  double previous_recall = 0.0;
  for (const PrPoint& p : curve) {
    s.area_under_curve += (p.recall - previous_recall) * p.precision;
    previous_recall = p.recall;
    if (p.false_positives == 0)
      s.recall_at_full_precision = std::max(s.recall_at_full_precision, p.recall);
  }
  return s;
}

}  // namespace

PrecisionRecall EvaluatePrecisionRecall(std::span<const EvaluatedMatch> matches) {
  PrecisionRecall pr;
  std::vector<std::size_t> order(matches.size());
  pr.curve.resize(matches.size());
  pr.curve.resize(PrecisionRecallCurve(matches, order, pr.curve));
  pr.summary = SummarisePrecisionRecall(matches, pr.curve);
  return pr;
}

HeadingErrorSummary SummariseHeadingErrors(std::span<double> errors_deg, int frames) {
  HeadingErrorSummary s;
  s.frames = frames;
  s.estimated = static_cast<int>(errors_deg.size());
  if (errors_deg.empty())
    return s;
  for (double& e : errors_deg)
    e = std::fabs(e);
  std::sort(errors_deg.begin(), errors_deg.end());
  auto rank = [&](double share) {
    const auto k =
        static_cast<std::size_t>(std::ceil(share * static_cast<double>(errors_deg.size())));
    return errors_deg[std::max<std::size_t>(k, 1) - 1];
  };
  s.median_deg = rank(0.5);
  s.p90_deg = rank(0.9);
  s.max_deg = errors_deg.back();
  return s;
}

std::size_t RocCurve(std::span<const ScoredPair> pairs, std::span<std::size_t> order,
                     std::span<RocPoint> curve) {
  const std::size_t n = pairs.size();
  if (order.size() < n || curve.size() < n + 1)
    return 0;
  std::size_t positives = 0;
  for (const ScoredPair& p : pairs)
    positives += p.match ? 1 : 0;
  const std::size_t negatives = n - positives;
  if (positives == 0 || negatives == 0)
    return 0;
  std::iota(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), std::size_t{0});
  // Ties are consumed together below, so their order among themselves does not matter.
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
            [&](std::size_t a, std::size_t b) { return pairs[a].score > pairs[b].score; });
  std::size_t points = 0;
  curve[points++] = {std::numeric_limits<double>::infinity(), 0.0, 0.0};
  std::size_t tp = 0, fp = 0, i = 0;
  while (i < n) {
    const double threshold = pairs[order[i]].score;
    while (i < n && pairs[order[i]].score == threshold) {
      (pairs[order[i]].match ? tp : fp) += 1;
      ++i;
    }
    curve[points++] = {threshold, static_cast<double>(fp) / static_cast<double>(negatives),
                       static_cast<double>(tp) / static_cast<double>(positives)};
  }
  return points;
}

double RocArea(std::span<const RocPoint> curve) {
  double area = 0;
  for (std::size_t i = 1; i < curve.size(); ++i)
    area += (curve[i].false_positive_rate - curve[i - 1].false_positive_rate) *
            (curve[i].true_positive_rate + curve[i - 1].true_positive_rate) / 2.0;
  return area;
}

}  // namespace skyloc::dsp
