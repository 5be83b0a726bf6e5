// The full sky descriptor of a 640x480 frame (Otsu + sampling + SH + amplitudes) at
// L = 120 on the default unaliased grid (60 rings x 256), and its stages, so the two
// sampling paths (threshold the frame at the sample pixels vs write the full mask and
// sample it) are compared in the same run. Target: full descriptor <= 0.3 ms on one core.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sample_lut.h"
#include "skyloc/dsp/segmentation.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace {

using namespace skyloc::dsp;

constexpr int kWidth = 640;
constexpr int kHeight = 480;

Lens MakeLens() {
  LensParams p;
  p.width = kWidth;
  p.height = kHeight;
  p.fov_deg = 185.0;
  Lens lens;
  if (lens.Init(p) != LensError::kOk)
    std::abort();
  return lens;
}

// A street canyon with texture, so the histogram is not two spikes.
std::vector<std::uint8_t> Frame(const Lens& lens) {
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(kWidth * kHeight));
  Eigen::Vector3d ray;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const int texture = (x * 7 + y * 13) % 29;
      std::uint8_t v = 3;
      if (lens.PixelToRay(x, y, &ray))
        v = static_cast<std::uint8_t>(std::fabs(ray(1)) * 1.1 < ray(2) ? 190 + texture
                                                                       : 40 + texture);
      grey[static_cast<std::size_t>(y * kWidth + x)] = v;
    }
  }
  return grey;
}

ImageView View(const std::vector<std::uint8_t>& g) {
  return {g.data(), kWidth, kHeight, kWidth, PixelFormat::kGrey8};
}

enum class Cap : std::uint8_t { kOff, kGravity };

void BM_Descriptor(benchmark::State& state, SamplingPath path, Cap cap) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  SkyDescriptorOptions options;
  options.bands = 120;
  options.path = path;
  options.cap = {cap == Cap::kGravity, 30.0, 10.0};
  SkyDescriptor descriptor;
  if (!descriptor.Init(lens, options).ok())
    std::abort();
  std::vector<float> amplitudes(120);
  // A tilted robot: the cap's dot product per sample runs (the zenith is not the axis).
  const Attitude attitude = AttitudeFromRollPitch(0, 12.0, -20.0);
  for (auto _ : state) {
    descriptor.Compute(View(frame), amplitudes, nullptr, &attitude);
    benchmark::DoNotOptimize(amplitudes.data());
  }
}
BENCHMARK_CAPTURE(BM_Descriptor, direct, SamplingPath::kDirect, Cap::kOff)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Descriptor, via_mask, SamplingPath::kViaMask, Cap::kOff)
    ->Unit(benchmark::kMicrosecond);
// The gravity-aligned cap: the extra cost is one dot product and compare per
// sample (a cosine on the taper's samples only); the reference is `direct` above.
BENCHMARK_CAPTURE(BM_Descriptor, direct_gravity_cap, SamplingPath::kDirect, Cap::kGravity)
    ->Unit(benchmark::kMicrosecond);

// The descriptor on the grids of docs/SKY_DESCRIPTOR.md, "Grid": bands, rings on the upper
// hemisphere, longitudes; `direct` above (120 bands, 60 x 256) is the reference.
void BM_DescriptorGrid(benchmark::State& state) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  SkyDescriptorOptions options;
  options.bands = static_cast<int>(state.range(0));
  options.grid.rings = static_cast<int>(state.range(1));
  options.grid.longitudes = static_cast<int>(state.range(2));
  SkyDescriptor descriptor;
  if (!descriptor.Init(lens, options).ok())
    std::abort();
  std::vector<float> amplitudes(static_cast<std::size_t>(options.bands));
  for (auto _ : state) {
    descriptor.Compute(View(frame), amplitudes, nullptr, nullptr);
    benchmark::DoNotOptimize(amplitudes.data());
  }
}
BENCHMARK(BM_DescriptorGrid)
    ->ArgNames({"bands", "rings", "longitudes"})
    ->Args({64, 32, 128})   // the minimal grid for 64 bands (the default before 2026-11-26)
    ->Args({64, 48, 256})   // oversampled: the firmware's default
    ->Args({120, 60, 256})  // the minimal grid for 120 bands
    ->Args({120, 90, 512})  // oversampled
    ->Unit(benchmark::kMicrosecond);

// Stages: histogram + Otsu over the image circle.
void BM_Threshold(benchmark::State& state) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  SkySegmenter seg;
  SegmentationOptions options;
  options.histogram_step = static_cast<int>(state.range(0));
  if (seg.Init(lens, options) != SegmentationError::kOk)
    std::abort();
  SegmentationResult r;
  for (auto _ : state) {
    seg.Threshold(View(frame), &r);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_Threshold)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_WriteMask(benchmark::State& state) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  SkySegmenter seg;
  if (seg.Init(lens, {}) != SegmentationError::kOk)
    std::abort();
  std::vector<std::uint8_t> mask(frame.size());
  SegmentationResult r;
  for (auto _ : state) {
    seg.Segment(View(frame), {mask.data(), kWidth, kHeight, kWidth, PixelFormat::kGrey8}, &r);
    benchmark::DoNotOptimize(mask.data());
  }
}
BENCHMARK(BM_WriteMask)->Unit(benchmark::kMicrosecond);

// Sampling alone, from the frame with a threshold or from a ready mask; footprint 1 or 3.
void BM_Sample(benchmark::State& state) {
  const bool from_mask = state.range(0) != 0;
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  ShGrid grid;
  if (grid.Init(DefaultShGridConfig(120)) != ShError::kOk)
    std::abort();
  SampleLut lut;
  if (lut.Init(lens, grid, SampleLutOptions{static_cast<int>(state.range(1))}) !=
      SampleLutError::kOk)
    std::abort();
  std::vector<std::uint8_t> mask(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i)
    mask[i] = frame[i] > 120 ? kMaskSky : kMaskGround;
  std::vector<float> samples(lut.size());
  for (auto _ : state) {
    if (from_mask)
      lut.SampleMask(View(mask), samples);
    else
      lut.SampleImage(View(frame), 120, samples);
    benchmark::DoNotOptimize(samples.data());
  }
}
BENCHMARK(BM_Sample)
    ->ArgNames({"from_mask", "footprint"})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({0, 3})
    ->Unit(benchmark::kMicrosecond);

// The SH stage alone on the same frame's samples, to read the breakdown above.
void BM_ProjectAndAmplitudes(benchmark::State& state) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> frame = Frame(lens);
  ShGrid grid;
  SampleLut lut;
  ShProjector projector;
  if (grid.Init(DefaultShGridConfig(120)) != ShError::kOk ||
      lut.Init(lens, grid, SampleLutOptions{}) != SampleLutError::kOk ||
      projector.Init(grid, 120) != ShError::kOk)
    std::abort();
  std::vector<float> samples(lut.size()), coefficients(projector.coefficient_count()),
      amplitudes(120);
  lut.SampleImage(View(frame), 120, samples);
  for (auto _ : state) {
    projector.Project(samples, coefficients);
    AmplitudeSpectrum(coefficients, 120, amplitudes);
    benchmark::DoNotOptimize(amplitudes.data());
  }
}
BENCHMARK(BM_ProjectAndAmplitudes)->Unit(benchmark::kMicrosecond);

// Heading of a matched frame, the two ways firmware::Pipeline::EstimateHeading runs
// them after the matcher picks a route frame, beside the descriptor: the route frame's
// strip (360 bytes, as the route database stores it) against a query frame turned by 25
// degrees. A skyline of a few harmonics over azimuth-textured ground, so 1D SURF finds a
// realistic number of features (the street canyon above is almost all wall at 0..20 deg).
std::vector<std::uint8_t> SkylineFrame(const Lens& lens, double turn_deg) {
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(kWidth * kHeight), 0);
  Eigen::Vector3d ray;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if (!lens.PixelToRay(x, y, &ray))
        continue;
      const double phi = std::atan2(ray.y(), ray.x()) - turn_deg * std::numbers::pi / 180.0;
      const double elevation = std::asin(ray.z()) * 180.0 / std::numbers::pi;
      const double skyline = 9.0 + 4.0 * std::sin(3.0 * phi) + 2.5 * std::cos(7.0 * phi) +
                             1.5 * std::sin(13.0 * phi + 1.0);
      const double ground = 70.0 + 20.0 * std::sin(5.0 * phi) + 10.0 * std::cos(11.0 * phi);
      grey[static_cast<std::size_t>(y * kWidth + x)] =
          static_cast<std::uint8_t>(elevation > skyline ? 215.0 : ground);
    }
  }
  return grey;
}

// What the firmware does per matched frame (app::Pipeline::EstimateHeading): the query's
// strip from the frame, the route frame's bytes to floats, then dsp::HeadingEstimator with
// (b) the cross-correlation alone, or (b) + (a) 1D SURF + RANSAC ([heading] surf = true,
// the default: (a) only where (b) is uncertain, which this pure turn is not). The
// surf_every_frame rows run (a) on every frame, as on a frame whose correlation is
// uncertain: against the same route frame each time (its features held), or against two
// route frames in turn (the stored strip's features found again every frame).
enum class HeadingRun { kCorrelation, kDefault, kSurfSameRouteFrame, kSurfNewRouteFrame };

void BM_Heading(benchmark::State& state, HeadingRun run) {
  const Lens lens = MakeLens();
  const std::vector<std::uint8_t> query = SkylineFrame(lens, 25.0);
  HorizonStrip horizon;
  if (horizon.Init(lens, HorizonStripOptions{}) != HorizonStripError::kOk)
    std::abort();
  const auto n = static_cast<std::size_t>(horizon.n_azimuth());
  std::vector<float> strip(n), stored(n);
  std::vector<std::vector<std::uint8_t>> route(2, std::vector<std::uint8_t>(n));
  for (std::size_t r = 0; r < route.size(); ++r) {
    horizon.Extract(View(SkylineFrame(lens, 10.0 * static_cast<double>(r))), strip);
    for (std::size_t j = 0; j < n; ++j)
      route[r][j] = static_cast<std::uint8_t>(std::lround(strip[j]));
  }
  HeadingOptions options;
  options.surf = run != HeadingRun::kCorrelation;
  options.surf_every_frame =
      run == HeadingRun::kSurfSameRouteFrame || run == HeadingRun::kSurfNewRouteFrame;
  HeadingEstimator estimator;
  if (estimator.Init(horizon.n_azimuth(), options) != HeadingError::kOk)
    std::abort();
  HeadingEstimate estimate;
  std::size_t frame = 0;
  for (auto _ : state) {
    horizon.Extract(View(query), strip);
    const std::vector<std::uint8_t>& taught =
        route[run == HeadingRun::kSurfNewRouteFrame ? frame++ % route.size() : 0];
    for (std::size_t j = 0; j < n; ++j)
      stored[j] = taught[j];
    estimator.Estimate(stored, strip, &estimate);
    benchmark::DoNotOptimize(estimate);
  }
  state.counters["heading_deg"] = estimate.correlation_deg;
  if (options.surf) {
    state.counters["surf_deg"] = estimate.surf_deg;
    state.counters["inliers"] = estimate.surf_inliers;
  }
}
BENCHMARK_CAPTURE(BM_Heading, correlation, HeadingRun::kCorrelation)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Heading, correlation_and_surf, HeadingRun::kDefault)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Heading, surf_every_frame, HeadingRun::kSurfSameRouteFrame)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Heading, surf_every_frame_new_route_frame, HeadingRun::kSurfNewRouteFrame)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
