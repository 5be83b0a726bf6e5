// Whole-run batch SeqSLAM at dataset scale: 3576 x 3576 vanilla-sized
// descriptors (64 x 32 = 2048 values; synthetic, we have no Nordland frames), ds 10,
// v 0.8-1.2, R 10, centred window. The reference measured in the same run is the
// whole-matrix engine (BatchSeqSlam: one DifferenceColumn per query, N x M floats twice),
// what `skyloc eval --batch` ran before. Wall time (UseRealTime): the threaded runs use
// more than the calling thread. docs/BENCHMARKS.md, "Batch SeqSLAM at dataset scale".
//
//   build/bench/tests/bench/seqslam_batch_bench --benchmark_filter=Batch
//   SKYLOC_BENCH_LARGE=1 .../seqslam_batch_bench --benchmark_filter=30000
//     adds the 30,000 x 30,000 byte run (about a minute per core, ~200 MB).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <vector>

#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/seqslam_batch.h"
#include "support/synthetic_descriptors.h"
#include "tools/parallel.h"

namespace {

using skyloc::dsp::DescriptorRows;
using skyloc::dsp::SeqSlamMatch;
using skyloc::dsp::SeqSlamParams;

constexpr int kDim = 2048;

struct Run {
  int n = 0;
  std::vector<float> ref, query;
  std::vector<std::uint8_t> ref8, query8;
};

// Reference route and a query run over it at 1.05 route frames per frame with noise.
const Run& Nordland3576() {
  static const Run run = [] {
    Run r;
    r.n = 3576;
    skyloc::testing::SyntheticRoute route;
    route.dim = kDim;
    r.ref = route.Reference(r.n);
    r.query = route.Query(r.n, r.n, 0.0, 1.0, 1.5f);
    r.ref8.resize(r.ref.size());
    r.query8.resize(r.query.size());
    skyloc::dsp::QuantiseToBytes(r.ref, r.ref8);
    skyloc::dsp::QuantiseToBytes(r.query, r.query8);
    return r;
  }();
  return run;
}

void CountCorrect(benchmark::State& state, const std::vector<SeqSlamMatch>& m) {
  int correct = 0;
  for (std::size_t t = 0; t < m.size(); ++t)
    correct += m[t].valid && std::abs(m[t].reference - static_cast<int>(t)) <= 5 ? 1 : 0;
  state.counters["correct"] = correct;
}

// The reference: the whole-matrix engine, one thread.
void BM_BatchWholeMatrix(benchmark::State& state) {
  const Run& r = Nordland3576();
  std::vector<SeqSlamMatch> m(static_cast<std::size_t>(r.n));
  for (auto _ : state) {
    (void)skyloc::dsp::BatchSeqSlam(r.ref, r.query, kDim, SeqSlamParams{},
                                    skyloc::dsp::SeqSlamWindow::kCentred, m);
    benchmark::DoNotOptimize(m.data());
  }
  CountCorrect(state, m);
}
BENCHMARK(BM_BatchWholeMatrix)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void Blocked(benchmark::State& state, const DescriptorRows& ref, const DescriptorRows& query) {
  const int jobs = static_cast<int>(state.range(0));
  std::vector<SeqSlamMatch> m(static_cast<std::size_t>(query.count()));
  std::size_t bytes = 0;
  for (auto _ : state) {
    skyloc::dsp::BlockedSeqSlamOptions o;
    o.block_columns = std::max(256, 4 * jobs * skyloc::dsp::BlockedSeqSlam::kColumnGroup);
    skyloc::dsp::BlockedSeqSlam engine;
    if (engine.Init(ref, query, SeqSlamParams{}, skyloc::dsp::SeqSlamWindow::kCentred, o, m) !=
        skyloc::dsp::SeqSlamError::kOk) {
      state.SkipWithError("Init failed");
      return;
    }
    skyloc::tools::RunBlockedSeqSlam(engine, jobs);
    bytes = engine.AllocatedBytes();
    benchmark::DoNotOptimize(m.data());
  }
  CountCorrect(state, m);
  state.counters["store_MB"] = static_cast<double>(bytes) / 1e6;
}

void BM_BatchBlockedFloat(benchmark::State& state) {
  const Run& r = Nordland3576();
  Blocked(state, DescriptorRows::Floats(r.ref, kDim), DescriptorRows::Floats(r.query, kDim));
}
BENCHMARK(BM_BatchBlockedFloat)
    ->ArgName("jobs")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_BatchBlockedByte(benchmark::State& state) {
  const Run& r = Nordland3576();
  Blocked(state, DescriptorRows::Bytes(r.ref8, kDim), DescriptorRows::Bytes(r.query8, kDim));
}
BENCHMARK(BM_BatchBlockedByte)
    ->ArgName("jobs")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

// 30,000 x 30,000 in bytes, generated row by row (no float copy is kept): 2 x 61 MB of
// descriptors, the engine's store n x (block + ds - 1) floats and per-thread scratch.
void BM_BatchBlockedByte30000(benchmark::State& state) {
  constexpr int kN = 30000;
  skyloc::testing::SyntheticRoute route;
  route.dim = kDim;
  std::vector<std::uint8_t> ref(static_cast<std::size_t>(kN) * kDim),
      query(static_cast<std::size_t>(kN) * kDim);
  std::vector<float> row(kDim);
  for (int i = 0; i < kN; ++i) {
    const auto at = static_cast<std::size_t>(i) * kDim;
    route.Row(i, 0.0f, 0, row);
    skyloc::dsp::QuantiseToBytes(row, std::span<std::uint8_t>(ref).subspan(at, kDim));
    route.Row(i, 1.5f, static_cast<std::uint64_t>(i) + 1, row);
    skyloc::dsp::QuantiseToBytes(row, std::span<std::uint8_t>(query).subspan(at, kDim));
  }
  Blocked(state, DescriptorRows::Bytes(ref, kDim), DescriptorRows::Bytes(query, kDim));
}

const bool kLargeRegistered = [] {
  if (std::getenv("SKYLOC_BENCH_LARGE") != nullptr) {
    benchmark::RegisterBenchmark("BM_BatchBlockedByte30000", BM_BatchBlockedByte30000)
        ->ArgName("jobs")
        ->Arg(1)
        ->Arg(2)
        ->Unit(benchmark::kSecond)
        ->UseRealTime()
        ->Iterations(1);
  }
  return true;
}();

}  // namespace
