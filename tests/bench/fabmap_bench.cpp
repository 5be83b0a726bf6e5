// FAB-MAP 2.0 query cost (inverted index, app/tools/fabmap.h) against the route length:
// 1k, 10k and 100k reference places, with a 500-word vocabulary (200 distinct words per
// image: 40 % occupancy, what SIFT's 500 keypoints give on the simulated sky images) and a
// 5000-word one (4 %). Inference only: SIFT and quantisation are per image, not per place
// (docs/FABMAP.md, "Speed"). Target: a 10,000-frame comparison must not be slowed by it,
// i.e. well under the ~30 ms SIFT costs per frame.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "tools/chow_liu.h"
#include "tools/fabmap.h"

namespace {

using skyloc::tools::FabMap2;
using skyloc::tools::WordList;

WordList RandomImage(std::mt19937& rng, int words, int per_image) {
  std::vector<std::uint32_t> all(static_cast<std::size_t>(words));
  for (int q = 0; q < words; ++q)
    all[static_cast<std::size_t>(q)] = static_cast<std::uint32_t>(q);
  // A partial shuffle: the first per_image entries are a uniform random subset.
  for (int k = 0; k < per_image; ++k) {
    std::uniform_int_distribution<int> pick(k, words - 1);
    std::swap(all[static_cast<std::size_t>(k)], all[static_cast<std::size_t>(pick(rng))]);
  }
  WordList w(all.begin(), all.begin() + per_image);
  std::sort(w.begin(), w.end());
  return w;
}

void BM_FabMapQuery(benchmark::State& state) {
  const int places = static_cast<int>(state.range(0));
  const int words = static_cast<int>(state.range(1));
  const int per_image = 200;
  std::mt19937 rng(42);
  std::vector<WordList> training;
  for (int i = 0; i < 1000; ++i)
    training.push_back(RandomImage(rng, words, per_image));
  const auto tree = skyloc::tools::LearnChowLiuTree(training, words);
  FabMap2 fm;
  if (!tree.ok() || !fm.Init(*tree, {}).ok()) {
    state.SkipWithError("setup failed");
    return;
  }
  for (const WordList& s : training)
    (void)fm.AddTrainingSample(s);
  for (int i = 0; i < places; ++i)
    (void)fm.AddPlace(RandomImage(rng, words, per_image));
  std::vector<WordList> queries;
  for (int i = 0; i < 16; ++i)
    queries.push_back(RandomImage(rng, words, per_image));
  std::vector<double> post(static_cast<std::size_t>(places));
  double p_new = 0;
  std::size_t k = 0;
  for (auto _ : state) {
    const skyloc::Status s = fm.LogPosterior(queries[k++ % queries.size()], post, &p_new);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(post.data());
  }
  state.counters["places"] = places;
  state.counters["words"] = words;
}
BENCHMARK(BM_FabMapQuery)
    ->Args({1000, 500})
    ->Args({10000, 500})
    ->Args({100000, 500})
    ->Args({10000, 5000})
    ->Unit(benchmark::kMillisecond);

}  // namespace
