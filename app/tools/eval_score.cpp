#include "tools/eval_score.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <string_view>
#include <system_error>
#include <utility>

#include "firmware/pipeline.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/heading.h"

namespace skyloc::tools {

using drivers::DspStatus;

namespace {

bool ParseInt(std::string_view t, int* v) {
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *v);
  return ec == std::errc() && p == t.data() + t.size() && !t.empty();
}

// One data line of a ground-truth file.
Status ReadTruthLine(std::string_view s, const std::string& path, int line_no, int n_query,
                     int n_ref, std::vector<bool>* seen, GroundTruth* gt) {
  const std::size_t comma = s.find(',');
  int q = 0, r = 0;
  if (comma == std::string_view::npos || !ParseInt(s.substr(0, comma), &q) ||
      !ParseInt(s.substr(comma + 1), &r))
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s:%d: expected two integers 'query_index,reference_index'", path.c_str(),
                         line_no);
  if (q < 0 || q >= n_query)
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s:%d: query_index %d outside the query run's 0..%d", path.c_str(),
                         line_no, q, n_query - 1);
  if (r < -1 || r >= n_ref)
    return Status::Error(StatusCode::kInvalidArgument, "%s:%d: reference_index %d outside -1..%d",
                         path.c_str(), line_no, r, n_ref - 1);
  if ((*seen)[static_cast<std::size_t>(q)])
    return Status::Error(StatusCode::kInvalidArgument, "%s:%d: query_index %d given twice",
                         path.c_str(), line_no, q);
  (*seen)[static_cast<std::size_t>(q)] = true;
  gt->truth[static_cast<std::size_t>(q)] = dsp::TruthAtFrame(r);
  return Status::Ok();
}

}  // namespace

bool GroundTruth::IsCorrect(int query, int matched) const {
  const auto i = static_cast<std::size_t>(query);
  return dsp::MatchIsCorrect(matched, truth[i], tolerance, reference_xyz,
                             i < query_xyz.size() ? query_xyz[i] : dsp::Position3{});
}

Result<GroundTruth> ReadGroundTruthCsv(const std::string& path, int n_query, int n_ref,
                                       const dsp::MatchTolerance& tolerance) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open ground truth %s", path.c_str());
  }
  GroundTruth gt;
  gt.tolerance = tolerance;
  gt.description = "file " + path;
  gt.truth.assign(static_cast<std::size_t>(n_query), dsp::TruthInterval{});
  std::vector<bool> seen(static_cast<std::size_t>(n_query), false);
  char line[256];
  int line_no = 0;
  Status status;
  while (status.ok() && std::fgets(line, sizeof line, f) != nullptr) {
    ++line_no;
    std::string_view s(line);
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r'))
      s.remove_suffix(1);
    if (line_no == 1) {
      if (s != "query_index,reference_index")
        status = Status::Error(StatusCode::kInvalidArgument,
                               "%s:1: header must be 'query_index,reference_index'", path.c_str());
      continue;
    }
    if (!s.empty())
      status = ReadTruthLine(s, path, line_no, n_query, n_ref, &seen, &gt);
  }
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  SKYLOC_TRY(status);
  if (read_error)
    return Status::Error(StatusCode::kDataLoss, "cannot read %s", path.c_str());
  if (line_no == 0)
    return Status::Error(StatusCode::kInvalidArgument, "%s: empty file", path.c_str());
  return gt;
}

GroundTruth GroundTruthFromPositions(std::vector<dsp::Position3> reference,
                                     std::vector<dsp::Position3> query, double max_offset_m,
                                     const dsp::MatchTolerance& tolerance) {
  GroundTruth gt;
  gt.tolerance = tolerance;
  gt.reference_xyz = std::move(reference);
  gt.query_xyz = std::move(query);
  gt.truth.assign(gt.query_xyz.size(), dsp::TruthInterval{});
  dsp::GroundTruthFromPositions(gt.reference_xyz, gt.query_xyz, max_offset_m, gt.truth);
  return gt;
}

ScoredMatches ScoreMatches(const GroundTruth& truth, std::span<const dsp::SeqSlamMatch> matches) {
  ScoredMatches s;
  for (std::size_t q = 0; q < matches.size(); ++q) {
    const dsp::SeqSlamMatch& m = matches[q];
    if (!m.valid)
      continue;
    dsp::EvaluatedMatch e;
    e.uniqueness = m.uniqueness;
    e.has_ground_truth = truth.truth[q].has_truth();
    e.correct = truth.IsCorrect(static_cast<int>(q), m.reference);
    s.evaluated_queries.push_back(static_cast<int>(q));
    s.evaluated.push_back(e);
  }
  s.pr = dsp::EvaluatePrecisionRecall(s.evaluated);
  return s;
}

LocalisedCount CountLocalised(std::span<const dsp::LocalisationState> states,
                              const ScoredMatches& scored) {
  LocalisedCount c;
  for (std::size_t k = 0; k < scored.evaluated_queries.size(); ++k) {
    if (states[static_cast<std::size_t>(scored.evaluated_queries[k])] ==
        dsp::LocalisationState::kLocalised) {
      ++c.localised;
      c.correct += scored.evaluated[k].correct ? 1 : 0;
    }
  }
  return c;
}

Result<std::vector<Confirmation>> LandmarkConfirmation(const firmware::Config& config,
                                                       firmware::Matcher matcher,
                                                       const Strips& reference, const Strips& query,
                                                       const GroundTruth& truth,
                                                       std::span<const dsp::SeqSlamMatch> matches,
                                                       const ScoredMatches& scored) {
  std::vector<Confirmation> confirmation;
  if (reference.columns == 0 || reference.columns != query.columns)
    return confirmation;
  const dsp::HeadingOptions& options = config.heading.estimate;
  SKYLOC_TRY_ASSIGN(const auto ref_features,
                    StripFeatures(reference.bytes, reference.columns, options));
  SKYLOC_TRY_ASSIGN(const auto query_features, StripFeatures(query.bytes, query.columns, options));
  dsp::LandmarkMatcher landmarks;
  if (const dsp::Surf1dError e = landmarks.Init(options.max_features, options.matching);
      e != dsp::Surf1dError::kOk)
    return DspStatus(e, "surf1d");
  const auto n_ref = static_cast<int>(ref_features.size());
  std::vector<float> score(matches.size(), 0.0f);
  for (std::size_t q = 0; q < matches.size(); ++q) {
    const dsp::SeqSlamMatch& m = matches[q];
    if (!m.valid || m.reference < 0 || m.reference >= n_ref)
      continue;
    dsp::LandmarkMatch lm;
    (void)landmarks.Match(ref_features[static_cast<std::size_t>(m.reference)], query_features[q],
                          reference.columns, &lm);
    score[q] = lm.model_found ? static_cast<float>(lm.ransac_score) : 0.0f;
  }
  firmware::Config replay = config;
  replay.seqslam.matcher = matcher;
  for (const double threshold : {25.0, 50.0, 100.0, 200.0, 400.0}) {
    std::vector<dsp::SeqSlamMatch> gated(matches.begin(), matches.end());
    for (std::size_t q = 0; q < gated.size(); ++q)
      if (static_cast<double>(score[q]) < threshold)
        gated[q].valid = false;
    const std::vector<dsp::LocalisationState> states = firmware::ReplayStateMachine(replay, gated);
    Confirmation c;
    c.min_score = threshold;
    // Counted as the run's own LOCALISED frames: over the frames the matcher gave a match
    // (a frame past the ends of OpenSeqSLAM's centred window has none but may still show
    // LOCALISED), judged on the ungated match.
    for (const int q : scored.evaluated_queries) {
      const auto t = static_cast<std::size_t>(q);
      if (states[t] != dsp::LocalisationState::kLocalised)
        continue;
      ++c.count.localised;
      c.count.correct += truth.IsCorrect(q, matches[t].reference) ? 1 : 0;
    }
    confirmation.push_back(c);
  }
  return confirmation;
}

Result<HeadingErrors> EvaluateHeadings(const dsp::HeadingOptions& options, const Strips& reference,
                                       const Strips& query,
                                       std::span<const double> reference_yaw_deg,
                                       std::span<const double> query_yaw_deg,
                                       std::span<const dsp::SeqSlamMatch> matches,
                                       const ScoredMatches& scored) {
  const auto n = static_cast<std::size_t>(reference.columns);
  // (a) on every frame: eval reports each way alone (the firmware runs (a) only where (b)
  // is uncertain; dsp/heading.h).
  dsp::HeadingOptions every_frame = options;
  every_frame.surf_every_frame = true;
  dsp::HeadingEstimator estimator;
  if (const dsp::HeadingError e = estimator.Init(reference.columns, every_frame);
      e != dsp::HeadingError::kOk)
    return DspStatus(e, "[heading]");
  std::vector<float> stored(n), test(n);
  std::vector<double> correlation, surf;  // signed errors, degrees
  int frames = 0;
  for (std::size_t k = 0; k < scored.evaluated.size(); ++k) {
    if (!scored.evaluated[k].correct)
      continue;
    const auto q = static_cast<std::size_t>(scored.evaluated_queries[k]);
    const auto r = static_cast<std::size_t>(matches[q].reference);
    for (std::size_t j = 0; j < n; ++j) {
      stored[j] = reference.bytes[r * n + j];
      test[j] = query.bytes[q * n + j];
    }
    const double truth = dsp::WrapDegrees(query_yaw_deg[q] - reference_yaw_deg[r]);
    dsp::HeadingEstimate e;
    if (const dsp::HeadingError he = estimator.Estimate(stored, test, &e);
        he != dsp::HeadingError::kOk)
      return DspStatus(he, "heading of query frame %zu", q);
    ++frames;
    if (e.has_correlation)
      correlation.push_back(dsp::WrapDegrees(e.correlation_deg - truth));
    if (e.has_surf)
      surf.push_back(dsp::WrapDegrees(e.surf_deg - truth));
  }
  HeadingErrors h;
  h.correlation = dsp::SummariseHeadingErrors(correlation, frames);
  h.surf = dsp::SummariseHeadingErrors(surf, frames);
  return h;
}

std::string EvalRun::label() const {
  return std::string(ScoredDescriptorName(descriptor)) + " " + matcher_name +
         " ds=" + std::to_string(ds);
}

void ScoreRun(const firmware::Config& config, const GroundTruth& truth, EvalRun* run) {
  firmware::Config replay = config;
  replay.seqslam.matcher = run->matcher;
  run->states = firmware::ReplayStateMachine(replay, run->matches);
  run->scored = ScoreMatches(truth, run->matches);
  run->localised = CountLocalised(run->states, run->scored);
}

}  // namespace skyloc::tools
