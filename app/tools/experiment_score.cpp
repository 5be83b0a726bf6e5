// ScoreRuns (tools/experiment.h): an experiment's pair of runs matched and scored by the
// evaluation library, the functions `skyloc eval` uses.
#include <utility>
#include <vector>

#include "skyloc/dsp/vanilla_descriptor.h"
#include "tools/eval_match.h"
#include "tools/eval_score.h"
#include "tools/experiment.h"
#include "tools/fabmap_eval.h"

namespace skyloc::tools {

using sim::TrajectoryPoint;

namespace {

Status FabmapRunMatches(const RunDescriptors& reference, const RunDescriptors& query,
                        const ExperimentOptions& options, std::vector<dsp::SeqSlamMatch>* matches) {
  if (options.fabmap_vocabulary == nullptr ||
      reference.fabmap_words.size() != reference.trajectory.size() ||
      query.fabmap_words.size() != query.trajectory.size())
    return Status::Error(StatusCode::kFailedPrecondition,
                         "FAB-MAP: the runs were described without a vocabulary");
  SKYLOC_TRY_ASSIGN(const std::vector<FabmapQueryMatch> found,
                    LocaliseWithFabmap(*options.fabmap_vocabulary, reference.fabmap_words,
                                       query.fabmap_words, FabMapParams{}));
  // As `skyloc eval --method fabmap`: the most probable reference place, even when the new
  // place is more probable (its uniqueness is then >= 0.5 and the PR sweep drops it early).
  std::vector<dsp::SeqSlamMatch> places = FabmapMatches(found);
  places.resize(matches->size());
  *matches = std::move(places);
  return Status::Ok();
}

const std::vector<float>& DescriptorsOf(const RunDescriptors& run, ScoredDescriptor descriptor) {
  switch (descriptor) {
    case ScoredDescriptor::kSkyCap:
      return run.sky_cap;
    case ScoredDescriptor::kVanilla:
      return run.vanilla;
    case ScoredDescriptor::kSky:
    case ScoredDescriptor::kFabmap:
    case ScoredDescriptor::kSurf1d:
      break;
  }
  return run.sky;
}

Status SequenceMatches(const RunDescriptors& reference, const RunDescriptors& query,
                       ScoredDescriptor descriptor, firmware::Matcher matcher,
                       const ExperimentOptions& options, std::span<dsp::SeqSlamMatch> matches) {
  const int dim = descriptor == ScoredDescriptor::kVanilla ? dsp::kVanillaDescriptorSize
                                                           : options.config.descriptor.bands;
  const std::vector<float>& ref_descriptors = DescriptorsOf(reference, descriptor);
  const std::vector<float>& query_descriptors = DescriptorsOf(query, descriptor);
  if (ref_descriptors.empty() || query_descriptors.empty())
    return Status::Error(StatusCode::kFailedPrecondition,
                         "the runs were described without that descriptor");
  const auto rows = [dim](const std::vector<float>& d) {
    return DescriptorRows{dim, static_cast<int>(d.size() / static_cast<std::size_t>(dim)), d, {}};
  };
  MatcherSettings settings;
  settings.matcher = matcher;
  settings.filter = options.filter;
  settings.filter.sequence_length = options.seqslam.sequence_length;
  settings.openseqslam = options.seqslam;
  settings.storage = options.config.capacities.route_storage;
  return MatchRows(rows(ref_descriptors), rows(query_descriptors), settings, matches);
}

std::vector<dsp::Position3> PositionsOf(const RunDescriptors& run) {
  std::vector<dsp::Position3> p;
  for (const TrajectoryPoint& t : run.trajectory)
    p.push_back({t.pose.x_m, t.pose.y_m, t.pose.z_m});
  return p;
}

// Precision-recall of the matches against the position ground truth, as `skyloc eval`.
void ScoreAgainstPositions(const RunDescriptors& reference, const RunDescriptors& query,
                           const ExperimentOptions& options, std::vector<dsp::SeqSlamMatch> matches,
                           MethodScore* out) {
  // A full lap of a closed route: its last frame is next to its first.
  const dsp::MatchTolerance tolerance{
      options.tolerance_frames, 0,
      reference.closed_loop ? static_cast<int>(reference.trajectory.size()) : 0};
  GroundTruth truth = GroundTruthFromPositions(PositionsOf(reference), PositionsOf(query),
                                               options.max_offset_m, tolerance);
  ScoredMatches scored = ScoreMatches(truth, matches);
  out->matched.assign(matches.size(), -1);
  out->correct.assign(matches.size(), false);
  for (std::size_t k = 0; k < scored.evaluated_queries.size(); ++k) {
    const auto q = static_cast<std::size_t>(scored.evaluated_queries[k]);
    out->matched[q] = matches[q].reference;
    out->correct[q] = scored.evaluated[k].correct;
  }
  out->truth = std::move(truth.truth);
  out->curve = std::move(scored.pr.curve);
  out->summary = scored.pr.summary;
  out->matches = std::move(matches);
}

}  // namespace

Status ScoreRuns(const RunDescriptors& reference, const RunDescriptors& query,
                 ScoredDescriptor descriptor, firmware::Matcher matcher,
                 const ExperimentOptions& options, MethodScore* out) {
  std::vector<dsp::SeqSlamMatch> matches(query.trajectory.size());
  if (descriptor == ScoredDescriptor::kFabmap) {
    SKYLOC_TRY(FabmapRunMatches(reference, query, options, &matches));
  } else {
    SKYLOC_TRY(SequenceMatches(reference, query, descriptor, matcher, options, matches));
  }
  ScoreAgainstPositions(reference, query, options, std::move(matches), out);
  return Status::Ok();
}

}  // namespace skyloc::tools
