// FAB-MAP 2.0 inference (Cummins & Newman, IJRR 2011) with the Chow-Liu approximation, in
// its inverted-index form: each place is stored as the sparse list of words seen there, and
// a query costs time in the number of (query word, place containing it) pairs, not in
// vocabulary x places. Formulas and defaults follow OpenFABMAP 2 (Glover et al., ICRA 2012;
// src/fabmap.cpp, FabMap2 and InferBinary::PzqGzpqL); the comments say where this departs.
// docs/FABMAP.md has the derivation.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/platform/status.h"
#include "tools/chow_liu.h"

namespace skyloc::tools {

struct FabMapParams {
  // The detector model p(z | e): how often a word that exists in the scene is detected, and
  // how often one that does not is detected anyway. OpenFABMAP's defaults (settings.yml
  // PzGe 0.39, PzGne 0). Need 0 <= p_z_given_not_e < p_z_given_e <= 1.
  double p_z_given_e = 0.39;
  double p_z_given_not_e = 0.0;
  // OpenFABMAP's sFactor: the posterior is blended with a uniform one, p' = s p + (1-s)/n,
  // so no hypothesis is ever exactly 0 or 1.
  double smoothing = 0.99;
  // Prior probability that a query is a new place; each of the n reference places gets
  // (1 - prior) / n. OpenFABMAP applies its Pnew = 0.9 only with its motion model and is
  // otherwise uniform over n + 1 hypotheses; we always apply it (departure), so the
  // new-place hypothesis does not fade as the route grows. 0 < prior < 1.
  double new_place_prior = 0.9;
};

Status CheckFabMapParams(const FabMapParams& p);

// p(z_q | z_parent(q), L): word q's likelihood given its Chow-Liu parent's state in the same
// query and whether the word was seen at place L (`place_has_q`); OpenFABMAP's
// InferBinary::PzqGzpqL. The place's own observation gives p(e_q | L) through the detector
// model with p(e_q) = p(z_q) as prior (InferBinary::PeqGLzq).
double WordLikelihood(const ChowLiuTree& tree, const FabMapParams& p, int q, bool zq, bool zpq,
                      bool place_has_q);

class FabMap2 {
 public:
  // Precomputes the four log-ratio tables of OpenFABMAP's FabMap2 constructor (d1..d4) and
  // each word's children.
  Status Init(const ChowLiuTree& tree, const FabMapParams& params);

  // A training image for the sampled new-place model: p(Z | new place) is the mean of the
  // likelihoods of the query at the training images (FAB-MAP 2.0 supports only the sampled
  // model; OpenFABMAP's FabMap2 asserts SAMPLED and uses every training image).
  Status AddTrainingSample(std::span<const std::uint32_t> words);
  // A reference place, with the words seen there (a WordList: ascending, distinct).
  Status AddPlace(std::span<const std::uint32_t> words);

  int places() const { return static_cast<int>(place_default_.size()); }
  int training_samples() const { return static_cast<int>(sample_default_.size()); }
  int words() const { return tree_.words; }

  // log p(Z | L_i) - log p(Z | L_empty) for every place i, where L_empty is a place that saw
  // no word: the constant cancels in the posterior, and it is what the index sums.
  Status PlaceLogLikelihoods(std::span<const std::uint32_t> query, std::span<double> out) const;
  // log p(Z | new place) - log p(Z | L_empty): log of the mean likelihood over the samples.
  Result<double> NewPlaceLogLikelihood(std::span<const std::uint32_t> query) const;

  // The log posterior before smoothing: out[i] = log p(L_i | Z) (out.size() == places()),
  // *log_new = log p(new place | Z); their exponentials sum to 1. In the log domain a
  // confident match keeps its distance from the runner-up (1 - p does not round to 0).
  Status LogPosterior(std::span<const std::uint32_t> query, std::span<double> out,
                      double* log_new) const;
  // The posterior over the places and a new place, smoothed: place_probability[i] for each
  // reference place (out.size() == places()), *new_place for the new place. They sum to 1.
  Status Localise(std::span<const std::uint32_t> query, std::span<double> place_probability,
                  double* new_place) const;

 private:
  // Adds an image to the index over one set of images: per-image defaults and word ->
  // images lists (after Init(), words checked against the vocabulary).
  Status AddToIndex(std::span<const std::uint32_t> words, std::vector<double>* defaults,
                    std::vector<std::vector<std::uint32_t>>* inverted);
  void IndexLikelihoods(std::span<const std::uint32_t> query, const std::vector<double>& defaults,
                        const std::vector<std::vector<std::uint32_t>>& inverted,
                        std::span<double> out) const;

  ChowLiuTree tree_;
  FabMapParams params_;
  bool initialised_ = false;
  std::vector<double> d1_, d2_, d3_, d4_;
  std::vector<std::vector<std::uint32_t>> children_;
  std::vector<double> place_default_, sample_default_;
  std::vector<std::vector<std::uint32_t>> place_index_, sample_index_;
};

}  // namespace skyloc::tools
