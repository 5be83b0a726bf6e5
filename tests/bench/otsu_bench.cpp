#include <benchmark/benchmark.h>

#include <random>

#include "skyloc/dsp/otsu.h"

namespace {

void BM_OtsuThreshold(benchmark::State& state) {
  std::mt19937 rng(1);
  skyloc::dsp::Histogram256 h{};
  for (auto& c : h)
    c = static_cast<std::uint32_t>(rng() % 5000);
  for (auto _ : state) {
    benchmark::DoNotOptimize(skyloc::dsp::OtsuThreshold(h));
  }
}
BENCHMARK(BM_OtsuThreshold);

}  // namespace
