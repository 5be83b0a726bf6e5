// Streaming SeqSLAM and route filter step cost at route lengths of 1k, 10k and 100k reference
// frames with 120-float descriptors (the paper's l = 120 amplitude spectrum). Targets: <= 0.25 ms
// at 10k and <= 2.5 ms at 100k on one core. The reference in the same run is one pass summing the
// whole database (the memory traffic the difference column cannot avoid), so the ratio step / read
// says how far the step is from the memory bound.
#include <benchmark/benchmark.h>

#include <cstring>
#include <random>
#include <vector>

#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"

namespace {

using skyloc::dsp::SeqSlamMatch;
using skyloc::dsp::SeqSlamParams;
using skyloc::dsp::StreamingSeqSlam;

constexpr int kDim = 120;

std::vector<float> RandomFloats(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v)
    x = uni(rng);
  return v;
}

void StreamingStep(benchmark::State& state, skyloc::dsp::ReferenceStorage storage) {
  const int n = static_cast<int>(state.range(0));
  SeqSlamParams p;  // ds 10, 5 velocities
  StreamingSeqSlam engine;
  if (engine.Init(p, kDim, n, storage) != skyloc::dsp::SeqSlamError::kOk) {
    state.SkipWithError("Init failed");
    return;
  }
  const std::vector<float> db = RandomFloats(static_cast<std::size_t>(n) * kDim, 1);
  for (int r = 0; r < n; ++r) {
    (void)engine.AddReference(
        std::span<const float>(db).subspan(static_cast<std::size_t>(r) * kDim, kDim));
  }
  const std::vector<float> queries = RandomFloats(16 * kDim, 2);
  SeqSlamMatch m;
  int t = 0;
  // Fill the ring first so every timed step runs the search.
  for (; t < p.sequence_length; ++t) {
    (void)engine.Step(
        std::span<const float>(queries).subspan(static_cast<std::size_t>(t % 16) * kDim, kDim), &m);
  }
  for (auto _ : state) {
    (void)engine.Step(
        std::span<const float>(queries).subspan(static_cast<std::size_t>(t % 16) * kDim, kDim), &m);
    benchmark::DoNotOptimize(m);
    ++t;
  }
  state.counters["bytes_per_ref"] =
      static_cast<double>(StreamingSeqSlam::BytesPerReference(p, kDim, storage));
}

// Routes of 1,000, 10,000 and 100,000 places, timed in microseconds.
void RouteLengths(benchmark::internal::Benchmark* b) {
  b->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
}

void BM_StreamingStep(benchmark::State& state) {
  StreamingStep(state, skyloc::dsp::ReferenceStorage::kFloat32);
}
BENCHMARK(BM_StreamingStep)->Apply(RouteLengths);

// The database stored as bfloat16: half the bytes the difference column reads.
void BM_StreamingStepBFloat16(benchmark::State& state) {
  StreamingStep(state, skyloc::dsp::ReferenceStorage::kBFloat16);
}
BENCHMARK(BM_StreamingStepBFloat16)->Apply(RouteLengths);

// The parts of a step, to see where the time goes.
// The route filter (the firmware's default matcher) on the same routes and queries: one
// difference column, its z-score, the band minimum over K + 1 rows and the runner-up.
// Random frames are unrelated, so FinishRoute merges none: every frame is a row.
void RouteFilterStep(benchmark::State& state, skyloc::dsp::ReferenceStorage storage) {
  const int n = static_cast<int>(state.range(0));
  skyloc::dsp::RouteFilterParams p;  // ds 10, K 4
  skyloc::dsp::RouteFilter engine;
  if (engine.Init(p, kDim, n, storage) != skyloc::dsp::SeqSlamError::kOk) {
    state.SkipWithError("Init failed");
    return;
  }
  const std::vector<float> db = RandomFloats(static_cast<std::size_t>(n) * kDim, 1);
  for (int r = 0; r < n; ++r) {
    (void)engine.AddReference(
        std::span<const float>(db).subspan(static_cast<std::size_t>(r) * kDim, kDim));
  }
  if (engine.FinishRoute() != skyloc::dsp::SeqSlamError::kOk || engine.rows() != n) {
    state.SkipWithError("FinishRoute failed or merged random frames");
    return;
  }
  const std::vector<float> queries = RandomFloats(16 * kDim, 2);
  SeqSlamMatch m;
  int t = 0;
  for (auto _ : state) {
    (void)engine.Step(
        std::span<const float>(queries).subspan(static_cast<std::size_t>(t % 16) * kDim, kDim), &m);
    benchmark::DoNotOptimize(m);
    ++t;
  }
  state.counters["bytes_per_ref"] =
      static_cast<double>(skyloc::dsp::RouteFilter::BytesPerReference(kDim, storage));
}

void BM_RouteFilterStep(benchmark::State& state) {
  RouteFilterStep(state, skyloc::dsp::ReferenceStorage::kFloat32);
}
BENCHMARK(BM_RouteFilterStep)->Apply(RouteLengths);

void BM_RouteFilterStepBFloat16(benchmark::State& state) {
  RouteFilterStep(state, skyloc::dsp::ReferenceStorage::kBFloat16);
}
BENCHMARK(BM_RouteFilterStepBFloat16)->Apply(RouteLengths);

// The route held as 8-bit square-law codes with a power-of-two scale per row: a quarter
// of the float route's bytes.
void BM_RouteFilterStepCodes8(benchmark::State& state) {
  RouteFilterStep(state, skyloc::dsp::ReferenceStorage::kCodes8);
}
BENCHMARK(BM_RouteFilterStepCodes8)->Apply(RouteLengths);

// 16-bit linear codes with a power-of-two scale per row: the route file's own values
// (format 5), at half the float route's bytes.
void BM_RouteFilterStepCodes16(benchmark::State& state) {
  RouteFilterStep(state, skyloc::dsp::ReferenceStorage::kCodes16);
}
BENCHMARK(BM_RouteFilterStepCodes16)->Apply(RouteLengths);

void BM_DifferenceColumn(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const std::vector<float> db = RandomFloats(n * kDim, 1), q = RandomFloats(kDim, 2);
  std::vector<float> out(n);
  for (auto _ : state) {
    skyloc::dsp::DifferenceColumn(db, kDim, q, out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_DifferenceColumn)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

void BM_EnhanceColumn(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const std::vector<float> d = RandomFloats(n, 3);
  std::vector<float> out(n);
  for (auto _ : state) {
    skyloc::dsp::EnhanceColumn(d, 10, out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_EnhanceColumn)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

void BM_TrajectorySearch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  SeqSlamParams p;
  skyloc::dsp::TrajectorySearch search;
  (void)search.Init(p);
  const std::vector<float> cols = RandomFloats(static_cast<std::size_t>(n) * 10, 4);
  std::vector<const float*> order(10);
  for (std::size_t j = 0; j < 10; ++j)
    order[j] = cols.data() + j * static_cast<std::size_t>(n);
  std::vector<float> scores(static_cast<std::size_t>(n));
  for (auto _ : state)
    benchmark::DoNotOptimize(search.Search(order, n, 9, scores));
}
BENCHMARK(BM_TrajectorySearch)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// Reference: one sequential pass over the database (N x 120 floats), summed into four
// SIMD registers so the loop runs at the speed of the memory, not of an add chain. A
// step cannot be faster than this: the difference column must read every element.
void BM_ReadDatabase(benchmark::State& state) {
  using Float4 = float __attribute__((vector_size(16)));
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const std::vector<float> db = RandomFloats(n * kDim, 1);
  for (auto _ : state) {
    Float4 lanes[4] = {};
    for (std::size_t i = 0; i + 16 <= db.size(); i += 16) {
      for (std::size_t l = 0; l < 4; ++l) {
        Float4 v;
        std::memcpy(&v, db.data() + i + 4 * l, sizeof v);
        lanes[l] += v;
      }
    }
    benchmark::DoNotOptimize(lanes);
  }
}
BENCHMARK(BM_ReadDatabase)->Apply(RouteLengths);

}  // namespace
