// FAB-MAP 2.0 as a place-recognition method for `skyloc eval`: every reference frame is a
// place, every query frame is localised against them (docs/FABMAP.md, "Evaluation").
#pragma once

#include <span>
#include <string>
#include <vector>

#include "skyloc/platform/status.h"
#include "tools/fabmap.h"
#include "tools/vocabulary.h"

namespace skyloc::tools {

struct FabmapQueryMatch {
  int reference = -1;      // the most probable reference place
  double p_reference = 0;  // its posterior (unsmoothed)
  double p_new = 0;        // the new-place posterior (unsmoothed)
  // 1 - p_reference, from the log domain (the sum of every other hypothesis), so the PR
  // sweep can order confident matches that 1 - p would round to 0: lower is more distinct.
  double uniqueness = 1;
};

struct FabmapEvalTiming {
  double features_s = 0;   // SIFT + quantisation of both runs
  double inference_s = 0;  // LogPosterior over all queries
  int queries = 0;
  int places = 0;
};

// Every query image localised against the reference images, each one place, with the
// vocabulary's Chow-Liu tree, detector model (replacing params') and new-place samples.
// `skyloc eval --method fabmap` and `skyloc experiment` both localise through this.
Result<std::vector<FabmapQueryMatch>> LocaliseWithFabmap(const Vocabulary& vocabulary,
                                                         std::span<const WordList> reference,
                                                         std::span<const WordList> query,
                                                         FabMapParams params);

// Loads the vocabulary (params' detector model is replaced by the file's), computes the
// words of both runs and localises every query frame.
Result<std::vector<FabmapQueryMatch>> MatchWithFabmap(const std::string& vocabulary_path,
                                                      const std::string& reference_dir,
                                                      const std::string& query_dir,
                                                      FabMapParams params,
                                                      FabmapEvalTiming* timing);

}  // namespace skyloc::tools
