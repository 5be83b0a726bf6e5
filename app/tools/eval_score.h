// Scoring for `skyloc eval` and the experiments: the ground truth of a pair of runs (a
// ground-truth file or the recorded positions, by the rule of dsp/place_metrics.h), the
// evaluated matches and their precision-recall, the firmware's state machine replayed over
// them, landmark confirmation and the heading error of the correctly matched frames.
// Offline (host tools): everything allocates.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "firmware/config.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/platform/status.h"
#include "tools/eval_match.h"

namespace skyloc::tools {

struct GroundTruth {
  std::vector<dsp::TruthInterval> truth;  // per query frame
  dsp::MatchTolerance tolerance;          // frames, or metres
  // The recorded positions (empty with a ground-truth file).
  std::vector<dsp::Position3> reference_xyz, query_xyz;
  std::string description;  // how the truth was made, for metrics.json

  // Whether query frame `query`'s match `matched` is right (dsp::MatchIsCorrect).
  bool IsCorrect(int query, int matched) const;
};

// A ground-truth file: "query_index,reference_index" then one line a query frame
// (reference -1: off the route); queries not listed have no truth.
Result<GroundTruth> ReadGroundTruthCsv(const std::string& path, int n_query, int n_ref,
                                       const dsp::MatchTolerance& tolerance);

// From the recorded positions: a query farther than max_offset_m from every reference
// frame has no truth (infinity: every query has one).
GroundTruth GroundTruthFromPositions(std::vector<dsp::Position3> reference,
                                     std::vector<dsp::Position3> query, double max_offset_m,
                                     const dsp::MatchTolerance& tolerance);

// The matches judged against the truth: only query frames with a match are evaluated.
struct ScoredMatches {
  std::vector<int> evaluated_queries;          // queries with a match, in order
  std::vector<dsp::EvaluatedMatch> evaluated;  // one per evaluated query
  dsp::PrecisionRecall pr;
};

ScoredMatches ScoreMatches(const GroundTruth& truth, std::span<const dsp::SeqSlamMatch> matches);

// LOCALISED frames among the evaluated ones and how many of them are correct.
struct LocalisedCount {
  int localised = 0;
  int correct = 0;
};
LocalisedCount CountLocalised(std::span<const dsp::LocalisationState> states,
                              const ScoredMatches& scored);

// Landmark confirmation at one threshold: the state machine replayed with a frame counting
// as a match only when the 1D SURF recognition score of its strip against the matched
// route frame's strip reaches `min_score`.
struct Confirmation {
  double min_score = 0;
  LocalisedCount count;
};

// Horizon strips of one run: `columns` bytes a frame (0: none).
struct Strips {
  int columns = 0;
  std::span<const std::uint8_t> bytes;
};

// Confirmation at 25, 50, 100, 200 and 400; none without strips in both runs.
Result<std::vector<Confirmation>> LandmarkConfirmation(const firmware::Config& config,
                                                       firmware::Matcher matcher,
                                                       const Strips& reference, const Strips& query,
                                                       const GroundTruth& truth,
                                                       std::span<const dsp::SeqSlamMatch> matches,
                                                       const ScoredMatches& scored);

// The heading of every correctly matched query frame against its matched reference frame,
// from the two frames' strips (dsp::HeadingEstimator, as the firmware), against the truth:
// the query frame's yaw minus the reference frame's (degrees, one per frame).
struct HeadingErrors {
  dsp::HeadingErrorSummary correlation, surf;
};
Result<HeadingErrors> EvaluateHeadings(const dsp::HeadingOptions& options, const Strips& reference,
                                       const Strips& query,
                                       std::span<const double> reference_yaw_deg,
                                       std::span<const double> query_yaw_deg,
                                       std::span<const dsp::SeqSlamMatch> matches,
                                       const ScoredMatches& scored);

// One scored run of `skyloc eval`: a descriptor, a matcher and a sequence length.
struct EvalRun {
  ScoredDescriptor descriptor = ScoredDescriptor::kVanilla;
  firmware::Matcher matcher = firmware::Matcher::kRouteFilter;
  std::string matcher_name;  // firmware::NameOf(matcher), "fabmap2" or surf1d's "single"
  int ds = 0;
  std::vector<dsp::SeqSlamMatch> matches;      // per query frame
  std::vector<dsp::LocalisationState> states;  // per query frame: the state machine replayed
  ScoredMatches scored;
  LocalisedCount localised;
  bool heading_evaluated = false;
  HeadingErrors heading;
  std::vector<Confirmation> confirmation;
  std::string label() const;  // "sky filter ds=10"
};

// Replays the state machine ([state] of `config`, the run's matcher) and scores the run.
void ScoreRun(const firmware::Config& config, const GroundTruth& truth, EvalRun* run);

}  // namespace skyloc::tools
