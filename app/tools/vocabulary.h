// The FAB-MAP vocabulary file that `skyloc fabmap-train` writes and `skyloc eval --method
// fabmap` reads: the feature settings, the visual words (cluster centres), the Chow-Liu
// tree, the detector model p(z|e) and the training images' word lists (the sampled
// new-place model). Versioned and checksummed like the route database; docs/FABMAP.md,
// "Vocabulary file", has the byte layout.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "skyloc/platform/status.h"
#include "tools/chow_liu.h"

namespace skyloc::tools {

inline constexpr std::uint32_t kVocabularyVersion = 1;
inline constexpr std::uint32_t kDescriptorSift = 1;  // OpenCV SIFT, 128 floats
inline constexpr int kSiftDim = 128;

struct FeatureSettings {
  int width = 480;  // every image is resized to width x height before detection (the paper's)
  int height = 270;
  int max_features = 500;  // strongest SIFT keypoints kept per image
  std::uint32_t descriptor = kDescriptorSift;
  int descriptor_dim = kSiftDim;
};

struct Vocabulary {
  FeatureSettings features;
  int words = 0;
  std::vector<float> centres;  // words x descriptor_dim, row-major
  ChowLiuTree tree;
  double p_z_given_e = 0.39;  // the detector model the file was trained for
  double p_z_given_not_e = 0.0;
  std::vector<WordList> samples;  // training images, for the new-place model
};

// Checks the vocabulary is self-consistent (sizes, ids, a tree, probabilities in (0, 1)).
Status CheckVocabulary(const Vocabulary& v);

// Writes `path` atomically (path.tmp, fsync, rename).
Status SaveVocabulary(const std::string& path, const Vocabulary& v);
// Reads and verifies a vocabulary file; every failure is one message naming the file.
Result<Vocabulary> LoadVocabulary(const std::string& path);

}  // namespace skyloc::tools
