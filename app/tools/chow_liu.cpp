#include "tools/chow_liu.h"

#include <cmath>
#include <cstddef>
#include <limits>

namespace skyloc::tools {
namespace {

// OpenFABMAP's smoothing of every probability the model stores (ChowLiuTree::P and ::CP):
// 0.98 x frequency + 0.01, so a word never seen (or always seen) in training cannot make a
// likelihood exactly 0.
double Smoothed(std::int64_t count, std::int64_t total) {
  if (total == 0)
    return 0.01;  // OpenFABMAP's CP() for an empty condition: p(z = 1) = 0.01
  return 0.98 * static_cast<double>(count) / static_cast<double>(total) + 0.01;
}

double Term(double joint, double pa, double pb) {
  return joint > 0 ? joint * std::log(joint / (pa * pb)) : 0.0;
}

}  // namespace

Status CheckWordList(std::span<const std::uint32_t> list, int words) {
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (list[i] >= static_cast<std::uint32_t>(words)) {
      return Status::Error(StatusCode::kOutOfRange,
                           "word id %u is outside the vocabulary of %d words", list[i], words);
    }
    if (i > 0 && list[i] <= list[i - 1]) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "word list not strictly ascending at position %zu (%u after %u)", i,
                           list[i], list[i - 1]);
    }
  }
  return Status::Ok();
}

// Departs from OpenFABMAP (ChowLiuTree::calcMutInfo), which mixes smoothed marginals with
// unsmoothed joints, so its "mutual information" can be negative and is not the quantity
// the Chow-Liu theorem maximises. Here all four cells and both marginals are the same
// empirical frequencies, which makes the estimate >= 0 and 0 exactly for independence.
double BinaryMutualInformation(std::int64_t n, std::int64_t a, std::int64_t b, std::int64_t ab) {
  if (n <= 0)
    return 0.0;
  const double inv = 1.0 / static_cast<double>(n);
  const double pa1 = static_cast<double>(a) * inv, pb1 = static_cast<double>(b) * inv;
  const double pa0 = 1.0 - pa1, pb0 = 1.0 - pb1;
  const double p11 = static_cast<double>(ab) * inv;
  const double p10 = static_cast<double>(a - ab) * inv;
  const double p01 = static_cast<double>(b - ab) * inv;
  const double p00 = static_cast<double>(n - a - b + ab) * inv;
  return Term(p11, pa1, pb1) + Term(p10, pa1, pb0) + Term(p01, pa0, pb1) + Term(p00, pa0, pb0);
}

Result<ChowLiuTree> LearnChowLiuTree(std::span<const WordList> samples, int words) {
  if (samples.empty()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "Chow-Liu tree: no training images; give at least one");
  }
  if (words < 1 || words > 1000000) {
    return Status::Error(StatusCode::kOutOfRange,
                         "Chow-Liu tree: %d words; the vocabulary must have 1..1000000", words);
  }
  const auto nw = static_cast<std::size_t>(words);
  // Occurrence counts and the inverted index (word -> images containing it).
  std::vector<std::int64_t> count(nw, 0);
  for (std::size_t s = 0; s < samples.size(); ++s) {
    if (Status st = CheckWordList(samples[s], words); !st.ok())
      return st.AddContext("Chow-Liu tree: training image %zu", s);
    for (const std::uint32_t q : samples[s])
      ++count[q];
  }
  std::vector<std::size_t> start(nw + 1, 0);
  for (std::size_t q = 0; q < nw; ++q)
    start[q + 1] = start[q] + static_cast<std::size_t>(count[q]);
  std::vector<std::uint32_t> images(start[nw]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t s = 0; s < samples.size(); ++s)
      for (const std::uint32_t q : samples[s])
        images[fill[q]++] = static_cast<std::uint32_t>(s);
  }
  const auto n = static_cast<std::int64_t>(samples.size());

  // Prim: grow the tree from word 0, each step adding the outside word with the largest
  // mutual information to a word inside. best[v]/link[v]: v's best edge into the tree.
  ChowLiuTree tree;
  tree.words = words;
  tree.root = 0;
  tree.parent.assign(nw, 0);
  std::vector<double> best(nw, -std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> link(nw, 0);
  std::vector<bool> in_tree(nw, false);
  std::vector<std::int64_t> together(nw, 0);  // co-occurrence of the word just added
  std::size_t u = 0;
  for (std::size_t added = 0; added < nw; ++added) {
    in_tree[u] = true;
    tree.parent[u] = added == 0 ? static_cast<std::int32_t>(u) : link[u];
    // Co-occurrence of u with every word: walk the images containing u.
    std::fill(together.begin(), together.end(), 0);
    for (std::size_t k = start[u]; k < start[u + 1]; ++k)
      for (const std::uint32_t q : samples[images[k]])
        ++together[q];
    std::size_t next = nw;
    for (std::size_t v = 0; v < nw; ++v) {
      if (in_tree[v])
        continue;
      const double mi = BinaryMutualInformation(n, count[u], count[v], together[v]);
      if (mi > best[v]) {
        best[v] = mi;
        link[v] = static_cast<std::int32_t>(u);
      }
      if (next == nw || best[v] > best[next])
        next = v;
    }
    u = next;
  }

  // The conditionals along the edges, smoothed as OpenFABMAP does.
  tree.p_z.resize(nw);
  tree.p_z_given_parent.resize(nw);
  tree.p_z_given_no_parent.resize(nw);
  std::vector<std::uint8_t> present(nw, 0);
  std::vector<std::int64_t> with_parent(nw, 0);  // images with q and its parent
  for (const WordList& s : samples) {
    for (const std::uint32_t q : s)
      present[q] = 1;
    for (const std::uint32_t q : s)
      if (present[static_cast<std::size_t>(tree.parent[q])] != 0)
        ++with_parent[q];
    for (const std::uint32_t q : s)
      present[q] = 0;
  }
  for (std::size_t q = 0; q < nw; ++q) {
    tree.p_z[q] = Smoothed(count[q], n);
    if (q == static_cast<std::size_t>(tree.root)) {
      tree.p_z_given_parent[q] = tree.p_z[q];
      tree.p_z_given_no_parent[q] = tree.p_z[q];
      continue;
    }
    const std::int64_t parent_count = count[static_cast<std::size_t>(tree.parent[q])];
    tree.p_z_given_parent[q] = Smoothed(with_parent[q], parent_count);
    tree.p_z_given_no_parent[q] = Smoothed(count[q] - with_parent[q], n - parent_count);
  }
  return tree;
}

}  // namespace skyloc::tools
