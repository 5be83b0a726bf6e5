#include "tools/chow_liu.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace skyloc::tools {
namespace {

TEST(FabmapChowLiu, MutualInformationOfHandWorkedTables) {
  // Two perfectly coupled fair bits: I = H = ln 2.
  EXPECT_NEAR(BinaryMutualInformation(4, 2, 2, 2), std::log(2.0), 1e-12);
  // Independent fair bits (each cell 1/4): 0.
  EXPECT_NEAR(BinaryMutualInformation(4, 2, 2, 1), 0.0, 1e-12);
  // Anti-coupled: also ln 2.
  EXPECT_NEAR(BinaryMutualInformation(4, 2, 2, 0), std::log(2.0), 1e-12);
  // p11 = 0.3, p10 = 0.2, p01 = 0.1, p00 = 0.4 (n = 10), worked by hand:
  const double expected = 0.3 * std::log(0.3 / (0.5 * 0.4)) + 0.2 * std::log(0.2 / (0.5 * 0.6)) +
                          0.1 * std::log(0.1 / (0.5 * 0.4)) + 0.4 * std::log(0.4 / (0.5 * 0.6));
  EXPECT_NEAR(BinaryMutualInformation(10, 5, 4, 3), expected, 1e-12);
}

// Samples of `parent.size()` binary words drawn from a known tree: the root is present with
// probability 0.45; word q copies its parent's state with edge-specific strengths.
struct KnownTree {
  std::vector<int> parent;  // -1 for the root; parents come before children
  std::vector<double> p_if_parent, p_if_no_parent;
};

KnownTree MakeKnownTree() {
  KnownTree t;
  // A shape with a deep chain, a wide fan and leaves at several depths.
  t.parent = {-1, 0, 0, 1, 1, 2, 3, 3, 6, 6, 5, 10, 11, 0, 13, 8};
  for (std::size_t q = 0; q < t.parent.size(); ++q) {
    t.p_if_parent.push_back(0.72 + 0.015 * static_cast<double>(q % 7));
    t.p_if_no_parent.push_back(0.06 + 0.01 * static_cast<double>(q % 5));
  }
  return t;
}

std::vector<WordList> Draw(const KnownTree& t, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<WordList> out;
  std::vector<bool> z(t.parent.size());
  for (int i = 0; i < n; ++i) {
    WordList list;
    for (std::size_t q = 0; q < t.parent.size(); ++q) {
      const double p = t.parent[q] < 0                            ? 0.45
                       : z[static_cast<std::size_t>(t.parent[q])] ? t.p_if_parent[q]
                                                                  : t.p_if_no_parent[q];
      z[q] = u(rng) < p;
      if (z[q])
        list.push_back(static_cast<std::uint32_t>(q));
    }
    out.push_back(std::move(list));
  }
  return out;
}

std::set<std::pair<int, int>> UndirectedEdges(const std::vector<int>& parent_or_self) {
  std::set<std::pair<int, int>> edges;
  for (std::size_t q = 0; q < parent_or_self.size(); ++q) {
    const int p = parent_or_self[q];
    if (p < 0 || p == static_cast<int>(q))
      continue;
    edges.insert({std::min(p, static_cast<int>(q)), std::max(p, static_cast<int>(q))});
  }
  return edges;
}

TEST(FabmapChowLiu, RecoversTheTreeTheDataWasDrawnFrom) {
  const KnownTree truth = MakeKnownTree();
  const std::vector<WordList> samples = Draw(truth, 6000, 1234);
  const Result<ChowLiuTree> tree = LearnChowLiuTree(samples, static_cast<int>(truth.parent.size()));
  ASSERT_TRUE(tree.ok()) << tree.status().message();
  const std::vector<int> learned(tree->parent.begin(), tree->parent.end());
  EXPECT_EQ(UndirectedEdges(learned), UndirectedEdges(truth.parent));
  EXPECT_EQ(tree->parent[static_cast<std::size_t>(tree->root)], tree->root);
}

TEST(FabmapChowLiu, ConditionalsMatchTheGeneratingModel) {
  // Rooted at word 0 like the truth, every learned edge points the same way, so the
  // learned p(z | parent) estimate the truth's (through OpenFABMAP's 0.98 p + 0.01).
  const KnownTree truth = MakeKnownTree();
  const std::vector<WordList> samples = Draw(truth, 20000, 99);
  const Result<ChowLiuTree> tree = LearnChowLiuTree(samples, static_cast<int>(truth.parent.size()));
  ASSERT_TRUE(tree.ok()) << tree.status().message();
  ASSERT_EQ(tree->root, 0);
  EXPECT_NEAR(tree->p_z[0], 0.98 * 0.45 + 0.01, 0.015);
  for (std::size_t q = 1; q < truth.parent.size(); ++q) {
    ASSERT_EQ(tree->parent[q], truth.parent[q]) << "word " << q;
    EXPECT_NEAR(tree->p_z_given_parent[q], 0.98 * truth.p_if_parent[q] + 0.01, 0.03) << q;
    EXPECT_NEAR(tree->p_z_given_no_parent[q], 0.98 * truth.p_if_no_parent[q] + 0.01, 0.03) << q;
  }
}

TEST(FabmapChowLiu, RejectsBadInput) {
  const std::vector<WordList> unsorted = {{3, 1}};
  EXPECT_FALSE(LearnChowLiuTree(unsorted, 5).ok());
  const std::vector<WordList> outside = {{1, 7}};
  const Result<ChowLiuTree> r = LearnChowLiuTree(outside, 5);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(std::string(r.status().message()).find("training image 0"), std::string::npos);
  EXPECT_FALSE(LearnChowLiuTree({}, 5).ok());
}

}  // namespace
}  // namespace skyloc::tools
