#include "tools/fabmap.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace skyloc::tools {
namespace {

// p(z_q = z) as stored in the tree (OpenFABMAP's InferBase::Pzq).
double Pz(const ChowLiuTree& t, std::size_t q, bool z) {
  return z ? t.p_z[q] : 1.0 - t.p_z[q];
}

// p(z_q = z | z_parent = zp) (InferBase::PzqGzpq).
double PzGivenParent(const ChowLiuTree& t, std::size_t q, bool z, bool zp) {
  const double p1 = zp ? t.p_z_given_parent[q] : t.p_z_given_no_parent[q];
  return z ? p1 : 1.0 - p1;
}

// The detector model p(z | e) (InferBinary::PzqGeq).
double PzGivenE(const FabMapParams& p, bool z, bool e) {
  const double p1 = e ? p.p_z_given_e : p.p_z_given_not_e;
  return z ? p1 : 1.0 - p1;
}

double LogSumExp(std::span<const double> v) {
  double m = -std::numeric_limits<double>::infinity();
  for (const double x : v)
    m = std::max(m, x);
  double s = 0;
  for (const double x : v)
    s += std::exp(x - m);
  return m + std::log(s);
}

}  // namespace

Status CheckFabMapParams(const FabMapParams& p) {
  if (!(p.p_z_given_not_e >= 0 && p.p_z_given_not_e < p.p_z_given_e && p.p_z_given_e <= 1)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "FAB-MAP detector model p(z|e) %g, p(z|not e) %g: need 0 <= p(z|not e) "
                         "< p(z|e) <= 1 (OpenFABMAP's defaults are 0.39 and 0)",
                         p.p_z_given_e, p.p_z_given_not_e);
  }
  if (!(p.smoothing > 0 && p.smoothing <= 1)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "FAB-MAP smoothing %g: need 0 < s <= 1 (OpenFABMAP's sFactor is 0.99)",
                         p.smoothing);
  }
  if (!(p.new_place_prior > 0 && p.new_place_prior < 1)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "FAB-MAP new-place prior %g: need 0 < prior < 1 (default 0.9)",
                         p.new_place_prior);
  }
  return Status::Ok();
}

double WordLikelihood(const ChowLiuTree& t, const FabMapParams& p, int word, bool zq, bool zpq,
                      bool place_has_q) {
  const auto q = static_cast<std::size_t>(word);
  // p(e_q = 1 | L) from the place's one observation (InferBinary::PeqGLzq).
  const double a = PzGivenE(p, place_has_q, true) * Pz(t, q, true);
  const double b = PzGivenE(p, place_has_q, false) * Pz(t, q, false);
  const double pe1 = a / (a + b);
  // p(z_q | e_q, z_pq) = (1 + alpha / beta)^-1 (Cummins & Newman 2008, eq. 11), summed over
  // e_q weighted by p(e_q | L) (InferBinary::PzqGzpqL).
  double sum = 0;
  for (const bool e : {false, true}) {
    const double alpha = Pz(t, q, zq) * PzGivenE(p, !zq, e) * PzGivenParent(t, q, !zq, zpq);
    const double beta = Pz(t, q, !zq) * PzGivenE(p, zq, e) * PzGivenParent(t, q, zq, zpq);
    sum += (e ? pe1 : 1.0 - pe1) * beta / (alpha + beta);
  }
  return sum;
}

Status FabMap2::Init(const ChowLiuTree& tree, const FabMapParams& params) {
  SKYLOC_TRY(CheckFabMapParams(params));
  const auto n = static_cast<std::size_t>(tree.words);
  if (tree.words < 1 || tree.parent.size() != n || tree.p_z.size() != n ||
      tree.p_z_given_parent.size() != n || tree.p_z_given_no_parent.size() != n) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "FAB-MAP: the Chow-Liu tree's tables do not match its %d words",
                         tree.words);
  }
  tree_ = tree;
  params_ = params;
  d1_.assign(n, 0);
  d2_.assign(n, 0);
  d3_.assign(n, 0);
  d4_.assign(n, 0);
  children_.assign(n, {});
  place_default_.clear();
  sample_default_.clear();
  place_index_.assign(n, {});
  sample_index_.assign(n, {});
  for (std::size_t q = 0; q < n; ++q) {
    const std::int32_t parent = tree.parent[q];
    if (parent < 0 || static_cast<std::size_t>(parent) >= n) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "FAB-MAP: word %zu's Chow-Liu parent %d is not a word", q, parent);
    }
    const int w = static_cast<int>(q);
    // The log ratio of a word's likelihood at a place that saw it to one that did not, for
    // each (z_q, z_parent): d1 for (0, 0), and d2..d4 relative to d1, as OpenFABMAP.
    auto ratio = [&](bool zq, bool zpq) {
      return std::log(WordLikelihood(tree, params, w, zq, zpq, true) /
                      WordLikelihood(tree, params, w, zq, zpq, false));
    };
    d1_[q] = ratio(false, false);
    d2_[q] = ratio(false, true) - d1_[q];
    d3_[q] = ratio(true, false) - d1_[q];
    d4_[q] = ratio(true, true) - d1_[q];
    // Departure: OpenFABMAP lists the root as its own child; skipping it changes nothing
    // (a present word is never its own absent child) and saves a test per query.
    if (static_cast<std::size_t>(parent) != q)
      children_[static_cast<std::size_t>(parent)].push_back(static_cast<std::uint32_t>(q));
  }
  initialised_ = true;
  return Status::Ok();
}

Status FabMap2::AddToIndex(std::span<const std::uint32_t> words, std::vector<double>* defaults,
                           std::vector<std::vector<std::uint32_t>>* inverted) {
  if (!initialised_)
    return Status::Error(StatusCode::kFailedPrecondition, "FAB-MAP: Init() first");
  SKYLOC_TRY(CheckWordList(words, tree_.words));
  const auto id = static_cast<std::uint32_t>(defaults->size());
  double d = 0;
  for (const std::uint32_t q : words) {
    d += d1_[q];
    (*inverted)[q].push_back(id);
  }
  defaults->push_back(d);
  return Status::Ok();
}

Status FabMap2::AddTrainingSample(std::span<const std::uint32_t> words) {
  return AddToIndex(words, &sample_default_, &sample_index_);
}

Status FabMap2::AddPlace(std::span<const std::uint32_t> words) {
  return AddToIndex(words, &place_default_, &place_index_);
}

// OpenFABMAP's FabMap2::getIndexLikelihoods. Each image starts from its default (every word
// it saw, scored as if absent from the query with an absent parent: d1); then each query
// word q adds d3 or d4 at the images that saw q, and each child c of q absent from the
// query (z_c = 0 but z_parent = 1) adds d2 at the images that saw c. Words the image did not
// see contribute the same factor to every image and to L_empty, so they cancel.
void FabMap2::IndexLikelihoods(std::span<const std::uint32_t> query,
                               const std::vector<double>& defaults,
                               const std::vector<std::vector<std::uint32_t>>& inverted,
                               std::span<double> out) const {
  std::copy(defaults.begin(), defaults.end(), out.begin());
  auto in_query = [&](std::uint32_t w) {
    return std::binary_search(query.begin(), query.end(), w);
  };
  for (const std::uint32_t q : query) {
    const bool zpq = in_query(static_cast<std::uint32_t>(tree_.parent[q]));
    const double d = zpq ? d4_[q] : d3_[q];
    for (const std::uint32_t i : inverted[q])
      out[i] += d;
    for (const std::uint32_t c : children_[q]) {
      if (in_query(c))
        continue;
      for (const std::uint32_t i : inverted[c])
        out[i] += d2_[c];
    }
  }
}

Status FabMap2::PlaceLogLikelihoods(std::span<const std::uint32_t> query,
                                    std::span<double> out) const {
  if (!initialised_)
    return Status::Error(StatusCode::kFailedPrecondition, "FAB-MAP: Init() first");
  SKYLOC_TRY(CheckWordList(query, tree_.words));
  if (out.size() != place_default_.size()) {
    return Status::Error(StatusCode::kInvalidArgument, "FAB-MAP: %zu outputs for %zu places",
                         out.size(), place_default_.size());
  }
  IndexLikelihoods(query, place_default_, place_index_, out);
  return Status::Ok();
}

Result<double> FabMap2::NewPlaceLogLikelihood(std::span<const std::uint32_t> query) const {
  if (!initialised_)
    return Status::Error(StatusCode::kFailedPrecondition, "FAB-MAP: Init() first");
  SKYLOC_TRY(CheckWordList(query, tree_.words));
  if (sample_default_.empty()) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "FAB-MAP: the new-place model has no training samples");
  }
  std::vector<double> l(sample_default_.size());
  IndexLikelihoods(query, sample_default_, sample_index_, l);
  return LogSumExp(l) - std::log(static_cast<double>(l.size()));
}

Status FabMap2::LogPosterior(std::span<const std::uint32_t> query, std::span<double> out,
                             double* log_new) const {
  SKYLOC_TRY(PlaceLogLikelihoods(query, out));
  SKYLOC_TRY_ASSIGN(const double l_new, NewPlaceLogLikelihood(query));
  const std::size_t n = out.size();
  // Likelihood x prior, normalised (FabMap::normaliseDistribution, with the new-place prior
  // described in fabmap.h).
  const double log_place_prior =
      n > 0 ? std::log((1.0 - params_.new_place_prior) / static_cast<double>(n)) : 0.0;
  const double a_new = l_new + std::log(params_.new_place_prior);
  double m = a_new;
  for (double& x : out) {
    x += log_place_prior;
    m = std::max(m, x);
  }
  double sum = std::exp(a_new - m);
  for (const double x : out)
    sum += std::exp(x - m);
  const double log_total = m + std::log(sum);
  for (double& x : out)
    x -= log_total;
  *log_new = a_new - log_total;
  return Status::Ok();
}

Status FabMap2::Localise(std::span<const std::uint32_t> query, std::span<double> place_probability,
                         double* new_place) const {
  double log_new = 0;
  SKYLOC_TRY(LogPosterior(query, place_probability, &log_new));
  const std::size_t n = place_probability.size();
  const double s = params_.smoothing;
  const double uniform = (1.0 - s) / static_cast<double>(n + 1);
  for (double& x : place_probability)
    x = s * std::exp(x) + uniform;
  *new_place = s * std::exp(log_new) + uniform;
  return Status::Ok();
}

}  // namespace skyloc::tools
