#include "tools/fabmap_eval.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "tools/features.h"
#include "tools/vocabulary.h"

namespace skyloc::tools {
namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

}  // namespace

Result<std::vector<FabmapQueryMatch>> LocaliseWithFabmap(const Vocabulary& v,
                                                         std::span<const WordList> ref,
                                                         std::span<const WordList> query,
                                                         FabMapParams params) {
  params.p_z_given_e = v.p_z_given_e;
  params.p_z_given_not_e = v.p_z_given_not_e;
  FabMap2 fm;
  SKYLOC_TRY(fm.Init(v.tree, params));
  for (const WordList& s : v.samples)
    SKYLOC_TRY(fm.AddTrainingSample(s));
  for (const WordList& w : ref)
    SKYLOC_TRY(fm.AddPlace(w));
  std::vector<FabmapQueryMatch> out(query.size());
  std::vector<double> log_post(ref.size());
  for (std::size_t i = 0; i < query.size() && !ref.empty(); ++i) {
    double log_new = 0;
    SKYLOC_TRY(fm.LogPosterior(query[i], log_post, &log_new));
    const auto best = static_cast<std::size_t>(std::max_element(log_post.begin(), log_post.end()) -
                                               log_post.begin());
    // 1 - p(best) as the sum of the other hypotheses, in the log domain.
    double m = log_new;
    for (std::size_t k = 0; k < log_post.size(); ++k)
      if (k != best)
        m = std::max(m, log_post[k]);
    double sum = std::exp(log_new - m);
    for (std::size_t k = 0; k < log_post.size(); ++k)
      if (k != best)
        sum += std::exp(log_post[k] - m);
    FabmapQueryMatch& q = out[i];
    q.reference = static_cast<int>(best);
    q.p_reference = std::exp(log_post[best]);
    q.p_new = std::exp(log_new);
    q.uniqueness = std::min(1.0, std::exp(m + std::log(sum)));
  }
  return out;
}

Result<std::vector<FabmapQueryMatch>> MatchWithFabmap(const std::string& vocabulary_path,
                                                      const std::string& reference_dir,
                                                      const std::string& query_dir,
                                                      FabMapParams params,
                                                      FabmapEvalTiming* timing) {
  SKYLOC_TRY_ASSIGN(const Vocabulary v, LoadVocabulary(vocabulary_path));
  const auto t0 = std::chrono::steady_clock::now();
  SKYLOC_TRY_ASSIGN(const std::vector<WordList> ref, DatasetWords(reference_dir, v));
  SKYLOC_TRY_ASSIGN(const std::vector<WordList> query, DatasetWords(query_dir, v));
  const auto t1 = std::chrono::steady_clock::now();
  SKYLOC_TRY_ASSIGN(std::vector<FabmapQueryMatch> out, LocaliseWithFabmap(v, ref, query, params));
  const auto t2 = std::chrono::steady_clock::now();
  if (timing != nullptr) {
    timing->features_s = Seconds(t0, t1);
    timing->inference_s = Seconds(t1, t2);
    timing->queries = static_cast<int>(query.size());
    timing->places = static_cast<int>(ref.size());
  }
  return out;
}

}  // namespace skyloc::tools
