// Local features and visual words for the FAB-MAP baseline, through OpenCV (Debian's
// libopencv-dev 4.6). SIFT replaces the paper's SURF: SURF is patented/non-free and not in
// Debian's OpenCV, SIFT is in the main features2d module since 4.4 (docs/FABMAP.md,
// "Substitutions"). Every OpenCV call is wrapped: an OpenCV exception becomes a Status.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/platform/status.h"
#include "tools/chow_liu.h"
#include "tools/vocabulary.h"

namespace skyloc::tools {

// SIFT descriptors (n x 128 floats, appended to *out) of `image` (grey, RGB, BGR or YUYV)
// after resizing it to settings.width x settings.height (INTER_AREA; the aspect ratio is
// not kept: the paper's 480x270). At most settings.max_features, the strongest.
Status ExtractSift(const dsp::ImageView& image, const FeatureSettings& settings,
                   std::vector<float>* out);

// k-means++ (OpenCV cv::kmeans, KMEANS_PP_CENTERS, one attempt, 20 iterations) of `rows`
// descriptors of `dim` values into `words` centres. Deterministic for a given seed.
Status ClusterWords(std::span<const float> descriptors, int dim, int words, std::uint64_t seed,
                    std::vector<float>* centres);

// The words (nearest centre, Euclidean) of the descriptors, as a WordList.
Status Quantise(std::span<const float> descriptors, std::span<const float> centres, int dim,
                WordList* out);

// The words of one image over the vocabulary: its SIFT features (the vocabulary's feature
// settings), each assigned to its nearest centre. `descriptors` is scratch space.
Status ImageWords(const dsp::ImageView& image, const Vocabulary& vocabulary,
                  std::vector<float>* descriptors, WordList* out);

// Every frame of the dataset folder `dir` as a WordList over the vocabulary's words.
Result<std::vector<WordList>> DatasetWords(const std::string& dir, const Vocabulary& vocabulary);

struct TrainOptions {
  std::vector<std::string> datasets;  // training runs (separate from the evaluated ones)
  int words = 500;
  int max_cluster_descriptors = 40000;  // evenly subsampled before k-means
  int max_samples = 1000;  // training images kept for the new-place model (OpenFABMAP's NumSamples)
  FeatureSettings features;
  std::uint64_t seed = 1;
};

// Features of every training frame, the vocabulary by k-means++, each frame's words, the
// Chow-Liu tree of their occurrences, and the new-place samples. Progress goes to stderr.
Result<Vocabulary> TrainVocabulary(const TrainOptions& options);

}  // namespace skyloc::tools
