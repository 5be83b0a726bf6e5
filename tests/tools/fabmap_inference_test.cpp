#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "tools/chow_liu.h"
#include "tools/fabmap.h"

namespace skyloc::tools {
namespace {

// ---- The dense reference ----------------------------------------------------------------
// Written from Cummins & Newman (IJRR 2008, eqs. 9-12) with no log-ratio tables and no
// inverted index: log p(Z | L) = sum over EVERY word q of log p(z_q | z_pq, L), with
//   p(z_q | z_pq, L) = sum_e p(z_q | e_q = e, z_pq) p(e_q = e | L),
//   p(z_q | e_q, z_pq) = 1 / (1 + alpha / beta),
//   alpha = p(z_q) p(~z_q | e_q) p(~z_q | z_pq),  beta = p(~z_q) p(z_q | e_q) p(z_q | z_pq),
//   p(e_q | L) from L's own observation by Bayes with the prior p(e_q) = p(z_q).
double RefLogLikelihood(const ChowLiuTree& t, const FabMapParams& p, const std::vector<bool>& z,
                        const std::vector<bool>& place) {
  double total = 0;
  for (std::size_t q = 0; q < z.size(); ++q) {
    const bool zq = z[q];
    const bool zp = z[static_cast<std::size_t>(t.parent[q])];
    const double pz1 = t.p_z[q];
    const double pz_obs = zq ? pz1 : 1 - pz1;
    const double pc1 = zp ? t.p_z_given_parent[q] : t.p_z_given_no_parent[q];
    const double pc_obs = zq ? pc1 : 1 - pc1;
    const double det_e1 = place[q] ? p.p_z_given_e : 1 - p.p_z_given_e;
    const double det_e0 = place[q] ? p.p_z_given_not_e : 1 - p.p_z_given_not_e;
    const double pe1 = det_e1 * pz1 / (det_e1 * pz1 + det_e0 * (1 - pz1));
    double like = 0;
    for (int e = 0; e <= 1; ++e) {
      const double pz_given_e1 = e == 1 ? p.p_z_given_e : p.p_z_given_not_e;
      const double obs_given_e = zq ? pz_given_e1 : 1 - pz_given_e1;
      const double alpha = pz_obs * (1 - obs_given_e) * (1 - pc_obs);
      const double beta = (1 - pz_obs) * obs_given_e * pc_obs;
      like += (e == 1 ? pe1 : 1 - pe1) * beta / (alpha + beta);
    }
    total += std::log(like);
  }
  return total;
}

std::vector<bool> Dense(const WordList& w, int words) {
  std::vector<bool> v(static_cast<std::size_t>(words), false);
  for (const std::uint32_t q : w)
    v[q] = true;
  return v;
}

WordList RandomList(std::mt19937& rng, int words, double p) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  WordList w;
  for (int q = 0; q < words; ++q)
    if (u(rng) < p)
      w.push_back(static_cast<std::uint32_t>(q));
  return w;
}

TEST(FabmapInference, InvertedIndexEqualsDenseEvaluation) {
  constexpr int kWords = 12;
  std::mt19937 rng(7);
  // A tree learned from correlated data, so parents matter: word q often copies q - 1.
  std::vector<WordList> training;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    WordList w;
    bool prev = u(rng) < 0.4;
    for (int q = 0; q < kWords; ++q) {
      const bool z = q == 0 ? prev : (u(rng) < (prev ? 0.7 : 0.2));
      if (z)
        w.push_back(static_cast<std::uint32_t>(q));
      prev = z;
    }
    training.push_back(w);
  }
  const Result<ChowLiuTree> tree = LearnChowLiuTree(training, kWords);
  ASSERT_TRUE(tree.ok()) << tree.status().message();
  for (const FabMapParams params :
       {FabMapParams{}, FabMapParams{0.6, 0.05, 0.9, 0.5}, FabMapParams{0.39, 0.0, 1.0, 0.2}}) {
    FabMap2 fm;
    ASSERT_TRUE(fm.Init(*tree, params).ok());
    std::vector<WordList> places, samples;
    for (int i = 0; i < 25; ++i) {
      places.push_back(RandomList(rng, kWords, 0.35));
      ASSERT_TRUE(fm.AddPlace(places.back()).ok());
    }
    places.push_back({});  // an empty place is a place too
    ASSERT_TRUE(fm.AddPlace(places.back()).ok());
    for (int i = 0; i < 30; ++i) {
      samples.push_back(RandomList(rng, kWords, 0.3));
      ASSERT_TRUE(fm.AddTrainingSample(samples.back()).ok());
    }
    const std::vector<bool> empty(kWords, false);
    for (int k = 0; k < 40; ++k) {
      const WordList query = k == 0 ? WordList{} : RandomList(rng, kWords, 0.3);
      const std::vector<bool> z = Dense(query, kWords);
      const double base = RefLogLikelihood(*tree, params, z, empty);
      // Place likelihoods, relative to the empty place.
      std::vector<double> got(places.size());
      ASSERT_TRUE(fm.PlaceLogLikelihoods(query, got).ok());
      std::vector<double> ref_log(places.size());
      for (std::size_t i = 0; i < places.size(); ++i) {
        ref_log[i] = RefLogLikelihood(*tree, params, z, Dense(places[i], kWords));
        EXPECT_NEAR(got[i], ref_log[i] - base, 1e-9) << "query " << k << " place " << i;
      }
      // The new place: the mean likelihood over the training samples.
      double mean = 0;
      for (const WordList& s : samples)
        mean += std::exp(RefLogLikelihood(*tree, params, z, Dense(s, kWords)));
      mean /= static_cast<double>(samples.size());
      const Result<double> l_new = fm.NewPlaceLogLikelihood(query);
      ASSERT_TRUE(l_new.ok());
      EXPECT_NEAR(*l_new, std::log(mean) - base, 1e-9) << "query " << k;
      // The posterior: prior x likelihood, normalised, then smoothed.
      const double n = static_cast<double>(places.size());
      double total = params.new_place_prior * mean;
      for (const double l : ref_log)
        total += (1 - params.new_place_prior) / n * std::exp(l);
      std::vector<double> post(places.size());
      double p_new = -1;
      ASSERT_TRUE(fm.Localise(query, post, &p_new).ok());
      const double s = params.smoothing, uni = (1 - s) / (n + 1);
      EXPECT_NEAR(p_new, s * params.new_place_prior * mean / total + uni, 1e-9);
      double sum = p_new;
      for (std::size_t i = 0; i < places.size(); ++i) {
        EXPECT_NEAR(post[i],
                    s * (1 - params.new_place_prior) / n * std::exp(ref_log[i]) / total + uni,
                    1e-9);
        sum += post[i];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
    }
  }
}

// Distinct toy places: each a random set of 25 of 2000 words (two rarely share more than
// one or two). Training images (the
// vocabulary's separate run) are other places of the same kind.
struct Toy {
  static constexpr int kWords = 2000;
  std::mt19937 rng{2024};
  WordList RandomPlace() {
    std::vector<std::uint32_t> all(kWords);
    for (int q = 0; q < kWords; ++q)
      all[static_cast<std::size_t>(q)] = static_cast<std::uint32_t>(q);
    std::shuffle(all.begin(), all.end(), rng);
    WordList w(all.begin(), all.begin() + 25);
    std::sort(w.begin(), w.end());
    return w;
  }
  // A clean re-observation: each word detected again with probability 0.8, plus two
  // spurious words.
  WordList Observe(const WordList& place) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::uniform_int_distribution<int> any(0, kWords - 1);
    WordList w;
    for (const std::uint32_t q : place)
      if (u(rng) < 0.8)
        w.push_back(q);
    for (int k = 0; k < 2; ++k)
      w.push_back(static_cast<std::uint32_t>(any(rng)));
    std::sort(w.begin(), w.end());
    w.erase(std::unique(w.begin(), w.end()), w.end());
    return w;
  }
};

TEST(FabmapInference, RanksTheTruePlaceFirstAndFlagsAnUnseenPlace) {
  Toy toy;
  std::vector<WordList> training;
  for (int i = 0; i < 500; ++i)
    training.push_back(toy.Observe(toy.RandomPlace()));
  const Result<ChowLiuTree> tree = LearnChowLiuTree(training, Toy::kWords);
  ASSERT_TRUE(tree.ok()) << tree.status().message();
  FabMap2 fm;
  ASSERT_TRUE(fm.Init(*tree, FabMapParams{}).ok());
  for (const WordList& s : training)
    ASSERT_TRUE(fm.AddTrainingSample(s).ok());
  std::vector<WordList> places;
  for (int i = 0; i < 60; ++i) {
    places.push_back(toy.RandomPlace());
    ASSERT_TRUE(fm.AddPlace(toy.Observe(places.back())).ok());
  }
  std::vector<double> post(places.size());
  double p_new = 0;
  for (std::size_t i = 0; i < places.size(); ++i) {
    ASSERT_TRUE(fm.Localise(toy.Observe(places[i]), post, &p_new).ok());
    const auto best =
        static_cast<std::size_t>(std::max_element(post.begin(), post.end()) - post.begin());
    EXPECT_EQ(best, i) << "query of place " << i;
    EXPECT_GT(post[i], 0.9) << "query of place " << i;
    EXPECT_LT(p_new, 0.1) << "query of place " << i;
  }
  // Unseen places: the new place should carry most of the probability. A random place
  // can share a couple of rare words with some reference by chance, and FAB-MAP is then
  // (rightly, by its model) confident in that reference, so this is asked of 38 of 40.
  double mean_new = 0;
  int flagged = 0;
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(fm.Localise(toy.Observe(toy.RandomPlace()), post, &p_new).ok());
    flagged += p_new > 0.5 ? 1 : 0;
    mean_new += p_new / 40;
  }
  EXPECT_GE(flagged, 38);
  EXPECT_GT(mean_new, 0.85);
}

TEST(FabmapInference, RejectsBadParametersAndQueries) {
  const std::vector<WordList> training = {{0, 1}, {1, 2}, {0}};
  const Result<ChowLiuTree> tree = LearnChowLiuTree(training, 3);
  ASSERT_TRUE(tree.ok());
  FabMap2 fm;
  EXPECT_FALSE(fm.Init(*tree, FabMapParams{0.3, 0.3, 0.99, 0.9}).ok());
  EXPECT_FALSE(fm.Init(*tree, FabMapParams{0.39, 0.0, 0.99, 1.0}).ok());
  ASSERT_TRUE(fm.Init(*tree, FabMapParams{}).ok());
  ASSERT_TRUE(fm.AddPlace(WordList{0, 2}).ok());
  std::vector<double> post(1);
  double p_new = 0;
  // No training samples: the new-place model cannot be evaluated.
  EXPECT_FALSE(fm.Localise(WordList{0}, post, &p_new).ok());
  ASSERT_TRUE(fm.AddTrainingSample(WordList{1}).ok());
  EXPECT_TRUE(fm.Localise(WordList{0}, post, &p_new).ok());
  EXPECT_FALSE(fm.Localise(WordList{5}, post, &p_new).ok());
  EXPECT_FALSE(fm.AddPlace(WordList{2, 1}).ok());
}

}  // namespace
}  // namespace skyloc::tools
