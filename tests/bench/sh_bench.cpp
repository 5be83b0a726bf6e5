// Spherical-harmonic projection speed. The fast projector is measured against the naive
// reference (the paper's O(samples·L²) table product) in the same run; compare the two
// BM_*_PaperGrid times for the speed-up (target ≥ 100×). BM_FastProjectAndAmplitudes_Default
// is the per-frame cost on the default unaliased grid (target ≤ 0.1 ms on one core).
#include <benchmark/benchmark.h>

#include <complex>
#include <cstdio>
#include <random>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "skyloc/dsp/ring_fft.h"
#include "skyloc/dsp/sh_grid.h"
#include "skyloc/dsp/spherical_harmonics.h"

namespace {

using namespace skyloc::dsp;

constexpr int kBands = 120;

// A sky-like mask: a zenith cap with a ragged edge, so both FFT and Legendre sums see
// realistic content (the cost does not depend on it).
std::vector<float> SkyMask(const ShGrid& grid) {
  std::mt19937 rng(1);
  std::vector<float> f(grid.sample_count());
  for (std::size_t s = 0; s < f.size(); ++s) {
    const ShDirection d = grid.direction(s);
    f[s] = (d.theta < 1.0 + 0.2 * std::sin(5 * d.phi) && (rng() % 16) != 0) ? 1.0f : 0.0f;
  }
  return f;
}

struct Fixture {
  explicit Fixture(const ShGridConfig& config) {
    if (grid.Init(config) != ShError::kOk)
      std::abort();
    samples = SkyMask(grid);
    coeffs.resize(ShCoefficientCount(kBands));
    amplitudes.resize(kBands);
  }
  ShGrid grid;
  std::vector<float> samples, coeffs, amplitudes;
};

template <typename Projector>
void RunProjector(benchmark::State& state, const ShGridConfig& config) {
  Fixture fx(config);
  Projector projector;
  if (projector.Init(fx.grid, kBands) != ShError::kOk) {
    state.SkipWithError("projector Init failed");
    return;
  }
  for (auto _ : state) {
    projector.Project(fx.samples, fx.coeffs);
    AmplitudeSpectrum(fx.coeffs, kBands, fx.amplitudes);
    benchmark::DoNotOptimize(fx.amplitudes.data());
    benchmark::ClobberMemory();
  }
  state.counters["samples"] = static_cast<double>(fx.grid.sample_count());
}

void BM_NaiveProjectAndAmplitudes_PaperGrid(benchmark::State& state) {
  RunProjector<ShNaiveProjector>(state, PaperShGridConfig());
}
void BM_FastProjectAndAmplitudes_PaperGrid(benchmark::State& state) {
  RunProjector<ShProjector>(state, PaperShGridConfig());
}
void BM_FastProjectAndAmplitudes_Default(benchmark::State& state) {
  RunProjector<ShProjector>(state, DefaultShGridConfig(kBands));
}
void BM_FastProject_Default(benchmark::State& state) {
  Fixture fx(DefaultShGridConfig(kBands));
  ShProjector projector;
  projector.Init(fx.grid, kBands);
  for (auto _ : state) {
    projector.Project(fx.samples, fx.coeffs);
    benchmark::DoNotOptimize(fx.coeffs.data());
    benchmark::ClobberMemory();
  }
}
void BM_AmplitudeSpectrum(benchmark::State& state) {
  Fixture fx(DefaultShGridConfig(kBands));
  for (auto _ : state) {
    AmplitudeSpectrum(fx.coeffs, kBands, fx.amplitudes);
    benchmark::DoNotOptimize(fx.amplitudes.data());
  }
}
void BM_FastInit_Default(benchmark::State& state) {
  Fixture fx(DefaultShGridConfig(kBands));
  for (auto _ : state) {
    ShProjector projector;
    benchmark::DoNotOptimize(projector.Init(fx.grid, kBands));
  }
}

// The ring FFT against Eigen's bundled kissfft (one real FFT per ring) on the default grid:
// the reason RingFft exists.
void BM_RingFft_Default(benchmark::State& state) {
  Fixture fx(DefaultShGridConfig(kBands));
  RingFft fft;
  fft.Init(fx.grid.ring_count(), fx.grid.longitudes());
  std::vector<float> c(fft.bins() * static_cast<std::size_t>(fx.grid.ring_count())), s(c.size());
  for (auto _ : state) {
    fft.Forward(fx.samples, c, s);
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
}
void BM_EigenKissFftRings_Default(benchmark::State& state) {
  Fixture fx(DefaultShGridConfig(kBands));
  Eigen::FFT<float> fft;
  fft.SetFlag(Eigen::FFT<float>::HalfSpectrum);
  const int n = fx.grid.longitudes();
  const auto half = static_cast<std::size_t>(n / 2 + 1);
  std::vector<std::complex<float>> out(half * static_cast<std::size_t>(fx.grid.ring_count()));
  for (auto _ : state) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(fx.grid.ring_count()); ++i)
      fft.fwd(&out[i * half], &fx.samples[i * static_cast<std::size_t>(n)], n);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}

BENCHMARK(BM_NaiveProjectAndAmplitudes_PaperGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FastProjectAndAmplitudes_PaperGrid)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastProjectAndAmplitudes_Default)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastProject_Default)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AmplitudeSpectrum)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastInit_Default)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RingFft_Default)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EigenKissFftRings_Default)->Unit(benchmark::kMicrosecond);

}  // namespace
