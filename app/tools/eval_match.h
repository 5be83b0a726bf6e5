// Matching for `skyloc eval` and the experiments: which descriptor a run is scored on, one
// matcher over two runs' descriptor rows (the route filter, OpenSeqSLAM batch or
// streaming), FAB-MAP's places as matches, and the 1D SURF recognition score of every
// query frame against every reference frame. Offline (host tools): everything allocates.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "firmware/config.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/surf1d.h"
#include "skyloc/platform/status.h"
#include "tools/fabmap_eval.h"

namespace skyloc::tools {

// Which descriptor of a run is scored: the sky descriptor, the sky above the
// gravity-aligned cap, the vanilla (patch-normalised greyscale) descriptor, FAB-MAP 2.0's
// words (each query alone, no sequence) or the 1D SURF recognition score of the horizon
// strips. The order is the order `skyloc eval` reports them in.
enum class ScoredDescriptor : std::uint8_t { kSky, kSkyCap, kVanilla, kFabmap, kSurf1d };

// "sky", "sky_cap", "vanilla", "fabmap", "surf1d"; ParseScoredDescriptor is false for any
// other name.
const char* ScoredDescriptorName(ScoredDescriptor descriptor);
bool ParseScoredDescriptor(std::string_view name, ScoredDescriptor* out);

// One run's descriptors, `count` rows of `dim` values: floats (every matcher) and/or bytes
// (dsp::QuantiseToBytes; read by the batch OpenSeqSLAM only, when given).
struct DescriptorRows {
  int dim = 0;
  int count = 0;
  std::span<const float> floats;
  std::span<const std::uint8_t> bytes;
};

struct MatcherSettings {
  firmware::Matcher matcher = firmware::Matcher::kRouteFilter;
  dsp::RouteFilterParams filter;   // kRouteFilter; its sequence_length is the run's ds
  dsp::SeqSlamParams openseqslam;  // kOpenSeqSlam; its sequence_length is the run's ds
  bool streaming = false;          // kOpenSeqSlam: the causal engine instead of the centred batch
  // How the causal engines (the route filter, streaming OpenSeqSLAM) hold the reference
  // rows: [capacities] route_storage, as the firmware does.
  dsp::ReferenceStorage storage = dsp::ReferenceStorage::kFloat32;
  int jobs = 1;                    // threads of the batch engine; the matches do not depend on it
  const char* progress = nullptr;  // what a progress line on stderr calls the run; null: none
};

// Every query row matched against the reference rows (matches.size() == query.count).
// The batch engine is OpenSeqSLAM's, blocked: the same matches bit for bit as the whole
// matrix (docs/SEQSLAM.md).
Status MatchRows(const DescriptorRows& reference, const DescriptorRows& query,
                 const MatcherSettings& settings, std::span<dsp::SeqSlamMatch> matches);

// FAB-MAP 2.0's places as matches: each query's most probable reference place, uniqueness
// 1 - its posterior (lower = more distinct, as SeqSLAM's ratio, so the same PR sweep
// applies: accepting uniqueness <= u is accepting p(place | query) >= 1 - u).
std::vector<dsp::SeqSlamMatch> FabmapMatches(std::span<const FabmapQueryMatch> found);

// Every frame's 1D SURF features from its horizon strip (`columns` bytes a frame), the
// strongest options.max_features.
Result<std::vector<std::vector<dsp::Surf1dFeature>>> StripFeatures(
    std::span<const std::uint8_t> strips, int columns, const dsp::HeadingOptions& options);

// The recognition score (NN with RANSAC: sum of 1 / distance over the RANSAC inliers) of
// every query strip against every reference strip, query-major (n_query x n_ref), on `jobs`
// threads.
Result<std::vector<float>> Surf1dScores(std::span<const std::uint8_t> reference_strips,
                                        std::span<const std::uint8_t> query_strips, int columns,
                                        const dsp::HeadingOptions& options, int jobs);

// The best-scoring reference of one query's scores (higher = more alike). Uniqueness as
// SeqSLAM's, lower = more distinctive: the best score outside +-rwindow/2 frames of the
// best divided by the best. No match when every score is 0 (no RANSAC line anywhere).
dsp::SeqSlamMatch BestScore(std::span<const float> scores, int rwindow);

}  // namespace skyloc::tools
