// The Chow-Liu tree of binary word occurrences (FAB-MAP, Cummins & Newman 2008, sec. 3.2;
// docs/FABMAP.md): the tree-shaped distribution over "word q seen in the image" (z_q) that
// is closest in KL divergence to the training data. Its edges are the maximum spanning tree
// of the words' pairwise mutual information; each word keeps p(z_q) and p(z_q | z_parent).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/platform/status.h"

namespace skyloc::tools {

// One image as a bag of words: the distinct word ids seen in it, sorted ascending. FAB-MAP
// only uses whether a word occurs, never how often, so this is the whole observation.
using WordList = std::vector<std::uint32_t>;

// Checks that every id is < words and the list is strictly ascending.
Status CheckWordList(std::span<const std::uint32_t> list, int words);

struct ChowLiuTree {
  int words = 0;
  int root = 0;
  // parent[q]: q's parent word; parent[root] == root (as OpenFABMAP's tree matrix).
  std::vector<std::int32_t> parent;
  // p(z_q = 1), p(z_q = 1 | z_parent = 1), p(z_q = 1 | z_parent = 0), smoothed as OpenFABMAP
  // does (0.98 x frequency + 0.01) so no probability is 0 or 1. For the root both
  // conditionals equal p(z_q = 1): the root depends on nothing.
  std::vector<double> p_z;
  std::vector<double> p_z_given_parent;
  std::vector<double> p_z_given_no_parent;
};

// Mutual information (nats) of two binary variables from their counts in `n` samples:
// `a` and `b` samples with each present, `ab` with both. Plug-in (empirical) estimate.
double BinaryMutualInformation(std::int64_t n, std::int64_t a, std::int64_t b, std::int64_t ab);

// Learns the tree from training images (each a WordList over `words` words; at least one
// image, 1..1,000,000 words). Prim's algorithm on the complete mutual-information graph,
// with co-occurrence counts computed one row at a time from an inverted index: O(words^2 +
// sum of squared list lengths) time, O(words + total list length) memory. Ties go to the
// word found first (a fixed order), so the tree is the same on every machine.
Result<ChowLiuTree> LearnChowLiuTree(std::span<const WordList> samples, int words);

}  // namespace skyloc::tools
