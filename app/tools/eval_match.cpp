#include "tools/eval_match.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <optional>

#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/seqslam_batch.h"
#include "tools/parallel.h"
#include "tools/progress.h"

namespace skyloc::tools {

using drivers::DspStatus;
using firmware::Matcher;

namespace {

// Called with the query frames matched so far.
using MatchProgress = std::function<void(int done)>;

struct DescriptorName {
  const char* name;
  ScoredDescriptor descriptor;
};
constexpr DescriptorName kDescriptorNames[] = {{"sky", ScoredDescriptor::kSky},
                                               {"sky_cap", ScoredDescriptor::kSkyCap},
                                               {"vanilla", ScoredDescriptor::kVanilla},
                                               {"fabmap", ScoredDescriptor::kFabmap},
                                               {"surf1d", ScoredDescriptor::kSurf1d}};

std::span<const float> Row(const DescriptorRows& d, int i) {
  return d.floats.subspan(static_cast<std::size_t>(i) * static_cast<std::size_t>(d.dim),
                          static_cast<std::size_t>(d.dim));
}

// The firmware's engine, as repeat runs it: causal, one query at a time.
dsp::SeqSlamError RouteFilterMatches(const DescriptorRows& reference, const DescriptorRows& query,
                                     const dsp::RouteFilterParams& params,
                                     dsp::ReferenceStorage storage, const MatchProgress& progress,
                                     std::span<dsp::SeqSlamMatch> matches) {
  dsp::RouteFilter engine;
  dsp::SeqSlamError e = engine.Init(params, reference.dim, std::max(1, reference.count), storage);
  for (int r = 0; e == dsp::SeqSlamError::kOk && r < reference.count; ++r)
    e = engine.AddReference(Row(reference, r));
  if (e == dsp::SeqSlamError::kOk)
    e = engine.FinishRoute();
  for (int t = 0; e == dsp::SeqSlamError::kOk && t < query.count; ++t) {
    e = engine.Step(Row(query, t), &matches[static_cast<std::size_t>(t)]);
    progress(t + 1);
  }
  return e;
}

dsp::SeqSlamError StreamingMatches(const DescriptorRows& reference, const DescriptorRows& query,
                                   const dsp::SeqSlamParams& params, dsp::ReferenceStorage storage,
                                   const MatchProgress& progress,
                                   std::span<dsp::SeqSlamMatch> matches) {
  dsp::StreamingSeqSlam engine;
  dsp::SeqSlamError e = engine.Init(params, reference.dim, std::max(1, reference.count), storage);
  for (int r = 0; e == dsp::SeqSlamError::kOk && r < reference.count; ++r)
    e = engine.AddReference(Row(reference, r));
  for (int t = 0; e == dsp::SeqSlamError::kOk && t < query.count; ++t) {
    e = engine.Step(Row(query, t), &matches[static_cast<std::size_t>(t)]);
    progress(t + 1);
  }
  return e;
}

// OpenSeqSLAM's batch engine, blocked: n_ref x (block + ds - 1) differences instead of the
// whole matrix, on `jobs` threads.
dsp::SeqSlamError BatchMatches(const DescriptorRows& reference, const DescriptorRows& query,
                               const dsp::SeqSlamParams& params, int jobs,
                               const MatchProgress& progress,
                               std::span<dsp::SeqSlamMatch> matches) {
  const bool bytes = !reference.bytes.empty() && !query.bytes.empty();
  const auto rows = [bytes](const DescriptorRows& d) {
    return bytes ? dsp::DescriptorRows::Bytes(d.bytes, d.dim)
                 : dsp::DescriptorRows::Floats(d.floats, d.dim);
  };
  dsp::BlockedSeqSlamOptions options;
  // Enough column groups per block to keep every thread busy; the result does not depend
  // on the block size.
  options.block_columns = std::max(256, 4 * jobs * dsp::BlockedSeqSlam::kColumnGroup);
  dsp::BlockedSeqSlam engine;
  const dsp::SeqSlamError e = engine.Init(rows(reference), rows(query), params,
                                          dsp::SeqSlamWindow::kCentred, options, matches);
  if (e == dsp::SeqSlamError::kOk)
    RunBlockedSeqSlam(engine, jobs, progress);
  return e;
}

}  // namespace

const char* ScoredDescriptorName(ScoredDescriptor descriptor) {
  for (const DescriptorName& n : kDescriptorNames)
    if (n.descriptor == descriptor)
      return n.name;
  return "?";
}

bool ParseScoredDescriptor(std::string_view name, ScoredDescriptor* out) {
  for (const DescriptorName& n : kDescriptorNames) {
    if (name == n.name) {
      *out = n.descriptor;
      return true;
    }
  }
  return false;
}

Status MatchRows(const DescriptorRows& reference, const DescriptorRows& query,
                 const MatcherSettings& settings, std::span<dsp::SeqSlamMatch> matches) {
  if (matches.size() != static_cast<std::size_t>(query.count))
    return Status::Error(StatusCode::kInvalidArgument, "%zu matches for %d query frames",
                         matches.size(), query.count);
  std::optional<Progress> progress;
  if (settings.progress != nullptr)
    progress.emplace(settings.progress, "query frames matched", query.count);
  const MatchProgress update = [&progress](int done) {
    if (progress)
      progress->Update(done);
  };
  dsp::SeqSlamError e = dsp::SeqSlamError::kOk;
  if (settings.matcher == Matcher::kRouteFilter)
    e = RouteFilterMatches(reference, query, settings.filter, settings.storage, update, matches);
  else if (settings.streaming)
    e = StreamingMatches(reference, query, settings.openseqslam, settings.storage, update, matches);
  else
    e = BatchMatches(reference, query, settings.openseqslam, settings.jobs, update, matches);
  if (progress)
    progress->Finish();
  if (e != dsp::SeqSlamError::kOk) {
    const int ds = settings.matcher == Matcher::kRouteFilter ? settings.filter.sequence_length
                                                             : settings.openseqslam.sequence_length;
    return DspStatus(e, "%s ds %d", firmware::NameOf(settings.matcher), ds);
  }
  return Status::Ok();
}

std::vector<dsp::SeqSlamMatch> FabmapMatches(std::span<const FabmapQueryMatch> found) {
  std::vector<dsp::SeqSlamMatch> matches(found.size());
  for (std::size_t i = 0; i < found.size(); ++i) {
    const FabmapQueryMatch& f = found[i];
    dsp::SeqSlamMatch& m = matches[i];
    if (f.reference < 0)
      continue;
    m.valid = true;
    m.reference = m.row = m.start = f.reference;
    m.score = static_cast<float>(-std::log(std::max(f.p_reference, 1e-300)));
    m.uniqueness = static_cast<float>(f.uniqueness);
    m.confidence = 1.0f - m.uniqueness;
  }
  return matches;
}

Result<std::vector<std::vector<dsp::Surf1dFeature>>> StripFeatures(
    std::span<const std::uint8_t> strips, int columns, const dsp::HeadingOptions& options) {
  dsp::Surf1d surf;
  if (const dsp::Surf1dError e = surf.Init(columns, options.features); e != dsp::Surf1dError::kOk)
    return DspStatus(e, "surf1d");
  const auto n = static_cast<std::size_t>(columns);
  std::vector<float> strip(n);
  std::vector<dsp::Surf1dFeature> found(static_cast<std::size_t>(options.max_features));
  std::vector<std::vector<dsp::Surf1dFeature>> features(n > 0 ? strips.size() / n : 0);
  for (std::size_t i = 0; i < features.size(); ++i) {
    for (std::size_t c = 0; c < n; ++c)
      strip[c] = strips[i * n + c];
    int count = 0;
    if (const dsp::Surf1dError e = surf.Detect(strip, found, &count); e != dsp::Surf1dError::kOk)
      return DspStatus(e, "surf1d");
    features[i].assign(found.begin(), found.begin() + count);
  }
  return features;
}

Result<std::vector<float>> Surf1dScores(std::span<const std::uint8_t> reference_strips,
                                        std::span<const std::uint8_t> query_strips, int columns,
                                        const dsp::HeadingOptions& options, int jobs) {
  SKYLOC_TRY_ASSIGN(const auto ref_features, StripFeatures(reference_strips, columns, options));
  SKYLOC_TRY_ASSIGN(const auto query_features, StripFeatures(query_strips, columns, options));
  const std::size_t n_ref = ref_features.size();
  const std::size_t n_query = query_features.size();
  std::vector<float> scores(n_query * n_ref);
  const int n_query_int = static_cast<int>(n_query);
  const int workers = std::clamp(jobs, 1, std::max(1, n_query_int));
  std::vector<dsp::LandmarkMatcher> matchers(static_cast<std::size_t>(workers));
  for (dsp::LandmarkMatcher& m : matchers) {
    if (const dsp::Surf1dError e = m.Init(options.max_features, options.matching);
        e != dsp::Surf1dError::kOk)
      return DspStatus(e, "surf1d");
  }
  Progress progress("surf1d scores", "query frames", n_query_int);
  std::atomic<long> done{0};
  ParallelFor(workers, n_query_int, [&](int q, int worker) {
    const auto qi = static_cast<std::size_t>(q);
    for (std::size_t r = 0; r < n_ref; ++r) {
      dsp::LandmarkMatch m;
      // Sized for max_features, which bounds every feature list: cannot fail.
      (void)matchers[static_cast<std::size_t>(worker)].Match(ref_features[r], query_features[qi],
                                                             columns, &m);
      scores[qi * n_ref + r] = m.model_found ? static_cast<float>(m.ransac_score) : 0.0f;
    }
    const long finished = ++done;
    if (worker == 0)
      progress.Update(finished);
  });
  progress.Finish();
  return scores;
}

dsp::SeqSlamMatch BestScore(std::span<const float> scores, int rwindow) {
  dsp::SeqSlamMatch m;
  const auto best = std::max_element(scores.begin(), scores.end());
  if (best == scores.end() || !(*best > 0.0f))
    return m;
  const int r = static_cast<int>(best - scores.begin());
  float runner_up = 0.0f;
  for (int i = 0; i < static_cast<int>(scores.size()); ++i)
    if (std::abs(i - r) > rwindow / 2)
      runner_up = std::max(runner_up, scores[static_cast<std::size_t>(i)]);
  m.valid = true;
  m.reference = m.row = m.start = r;
  m.score = *best;
  m.uniqueness = runner_up / *best;
  m.confidence = 1.0f - m.uniqueness;
  return m;
}

}  // namespace skyloc::tools
