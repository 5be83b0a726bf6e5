// End-to-end frame latency of the firmware pipeline: a 640x480 UV frame in (already
// captured), the state out (sky descriptor -> streaming SeqSLAM over a 10,000-frame route
// -> state machine -> heading against the matched frame's strip -> status output). Target: <= 1 ms
// p99 on one core. The p50/p99/max counters come from the same LatencyHistogram the firmware
// prints. The reference in the same run is one read of the frame (the memory traffic no pipeline
// can avoid).
#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <numeric>
#include <vector>

#include "firmware/frame_loop.h"
#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/platform/latency.h"
#include "skyloc/sim/street_source.h"

namespace {

using namespace skyloc;
using namespace skyloc::firmware;

constexpr int kWidth = 640, kHeight = 480, kFrames = 32, kRouteFrames = 10000;

// What a fixture's pipeline runs, beside the default configuration.
enum class Variant {
  kAttitude,       // the default configuration with [attitude] on: the gravity cap
  kAttitude64,     // the same with 64 bands
  kMinimalGrid64,  // 64 bands on the minimal 32 x 128 grid, the default before 2026-11-26
  kBands64,        // 64 bands on their oversampled grid (48 x 256), the default before 2026-11-28
  kBands120,       // 120 bands on their oversampled grid (90 x 512), the default
  kBands64NoHeading,  // [heading] off: no strips, no heading
  kBands120NoHeading,
};

struct Fixture {
  MonotonicClock clock;
  Pipeline pipeline{clock};
  std::vector<std::vector<std::uint8_t>> images;
  bool ok = false;

  explicit Fixture(Variant variant) {
    Config config = DefaultConfig();
    config.capacities.route_frames = kRouteFrames;
    if (variant == Variant::kMinimalGrid64) {  // docs/SKY_DESCRIPTOR.md, "Grid"
      config.descriptor.bands = 64;
      config.descriptor.grid = GridPreset::kAuto;
      ResolveDescriptorGrid(&config.descriptor);
    }
    // The band count set, not taken from the defaults: each row keeps measuring what it names.
    if (variant == Variant::kBands64 || variant == Variant::kBands64NoHeading ||
        variant == Variant::kAttitude64) {
      config.descriptor.bands = 64;
      ResolveDescriptorGrid(&config.descriptor);
    }
    if (variant == Variant::kBands120 || variant == Variant::kBands120NoHeading) {
      config.descriptor.bands = 120;
      ResolveDescriptorGrid(&config.descriptor);
    }
    const bool heading =
        variant != Variant::kBands64NoHeading && variant != Variant::kBands120NoHeading;
    if (!heading)
      config.heading.strip.n_azimuth = 0;
    if (variant == Variant::kAttitude || variant == Variant::kAttitude64)
      config.attitude.kind = AttitudeKind::kSim;  // the pipeline's gravity cap
    if (!pipeline.Init(config).ok())
      return;
    sim::StreetOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.seed = 5;
    o.frames = kFrames;
    sim::FilmedStreet filmed(o);
    drivers::Camera& camera = filmed.camera;
    if (!camera.Open().ok() || !camera.Start().ok())
      return;
    RouteFrames route;
    if (!route
             .Allocate(kRouteFrames, static_cast<std::size_t>(pipeline.dim()),
                       pipeline.strip_settings().columns)
             .ok())
      return;
    std::vector<std::vector<float>> descriptors;
    std::vector<std::vector<std::uint8_t>> strips;  // [heading]: every matched frame's heading
    for (int i = 0; i < kFrames; ++i) {
      Result<drivers::Frame> f = camera.Capture(std::chrono::seconds(1));
      if (!f.ok())
        return;
      images.emplace_back(f->image.data, f->image.data + kWidth * kHeight);
      FrameResult r;
      if (!pipeline.Describe(f->image, &r).ok())
        return;
      descriptors.emplace_back(pipeline.descriptor().begin(), pipeline.descriptor().end());
      strips.emplace_back(pipeline.strip().begin(), pipeline.strip().end());
    }
    // A 10,000-frame route: the street's descriptors, each repeated with a small offset so
    // no two are equal (SeqSLAM's cost does not depend on the values).
    for (int i = 0; i < kRouteFrames; ++i) {
      std::vector<float> d = descriptors[static_cast<std::size_t>(i % kFrames)];
      for (float& v : d)
        v += 1e-4f * static_cast<float>(i / kFrames);
      if (!route.Append({}, d, strips[static_cast<std::size_t>(i % kFrames)]))
        return;
    }
    ok = pipeline.SetRoute(route).ok() && pipeline.heading_enabled() == heading;
  }
};

// Each fixture is built on first use only (a 10,000-frame route each).
Fixture& FixtureFor(Variant variant) {
  switch (variant) {
    case Variant::kAttitude: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kAttitude64: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kMinimalGrid64: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kBands64: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kBands120: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kBands64NoHeading: {
      static Fixture f(variant);
      return f;
    }
    case Variant::kBands120NoHeading:
      break;
  }
  static Fixture f(Variant::kBands120NoHeading);
  return f;
}

// attitude: [attitude] on, each frame's attitude from a 200 Hz IMU (the simulated twin of
// the IIO driver) through the attitude filter, 7 samples a frame at 30 fps, then the
// descriptor with the gravity cap.
void FrameToState(benchmark::State& state, Variant variant) {
  Fixture& fixture = FixtureFor(variant);
  const bool attitude = variant == Variant::kAttitude || variant == Variant::kAttitude64;
  if (!fixture.ok) {
    state.SkipWithError("fixture failed");
    return;
  }
  constexpr std::int64_t kFramePeriodNs = 33'333'333, kImuPeriodNs = 5'000'000;
  std::vector<dsp::ImuSample> samples(400'000);  // 2,000 s at 200 Hz: 60,000 frames
  const std::array<double, 3> up = dsp::UpFromRollPitch(8.0, -5.0);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k].timestamp_ns = static_cast<std::int64_t>(k) * kImuPeriodNs;
    for (std::size_t a = 0; a < 3; ++a)
      samples[k].accel_mps2[a] = static_cast<float>(dsp::kStandardGravity * up[a]);
  }
  drivers::SimulatedImu imu({}, samples);
  drivers::ImuAttitudeSource source(&imu, {});
  if (attitude && !source.Open().ok()) {
    state.SkipWithError("attitude source failed");
    return;
  }
  MonotonicClock clock;
  drivers::SimulatedStatusOutput status({}, &clock);
  (void)status.Open();
  LatencyHistogram histogram;
  std::uint64_t i = 0, with_heading = 0;
  for (auto _ : state) {
    drivers::Frame frame;
    const std::vector<std::uint8_t>& image = fixture.images[i % kFrames];
    frame.image = {image.data(), kWidth, kHeight, static_cast<std::size_t>(kWidth),
                   dsp::PixelFormat::kGrey8};
    frame.timestamp = Nanoseconds{static_cast<std::int64_t>(i) * kFramePeriodNs};
    frame.sequence = i++;
    const Nanoseconds t0 = clock.Now();
    FrameResult r;
    dsp::Attitude a;
    const dsp::Attitude* used = nullptr;
    if (attitude) {
      if (Result<dsp::Attitude> got = source.At(frame); got.ok()) {
        a = *got;
        used = &a;
      }
    }
    (void)fixture.pipeline.Localise(frame, &r, used);
    (void)status.Show(r.state, r.confidence, clock.Now());
    histogram.Record(clock.Now() - t0);
    with_heading += r.has_heading ? 1 : 0;
    benchmark::DoNotOptimize(r);
  }
  auto us = [](Nanoseconds d) { return static_cast<double>(d.count()) / 1000.0; };
  state.counters["p50_us"] = us(histogram.Percentile(50));
  state.counters["p99_us"] = us(histogram.Percentile(99));
  state.counters["max_us"] = us(histogram.max());
  // Matched frames run the heading (both ways, [heading] defaults) against the route's strip.
  state.counters["heading_share"] =
      i > 0 ? static_cast<double>(with_heading) / static_cast<double>(i) : 0.0;
}
// 64 bands on their oversampled grid, heading on: the default before 2026-11-28, one
// setting away ([descriptor] bands = 64); compare with BM_FrameToState120, the default.
void BM_FrameToState64(benchmark::State& state) {
  FrameToState(state, Variant::kBands64);
}
BENCHMARK(BM_FrameToState64)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// The default configuration (120 bands) with the attitude's gravity cap: compare with
// BM_FrameToState120.
void BM_FrameToStateWithAttitude(benchmark::State& state) {
  FrameToState(state, Variant::kAttitude);
}
BENCHMARK(BM_FrameToStateWithAttitude)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

void BM_FrameToStateWithAttitude64(benchmark::State& state) {
  FrameToState(state, Variant::kAttitude64);
}
BENCHMARK(BM_FrameToStateWithAttitude64)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// The default descriptor before 2026-11-26: 64 bands on the minimal 32 x 128 grid.
void BM_FrameToStateMinimalGrid64(benchmark::State& state) {
  FrameToState(state, Variant::kMinimalGrid64);
}
BENCHMARK(BM_FrameToStateMinimalGrid64)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// 120 bands on their oversampled grid (docs/SKY_DESCRIPTOR.md, "Grid"), heading on: the
// default's frame.
void BM_FrameToState120(benchmark::State& state) {
  FrameToState(state, Variant::kBands120);
}
BENCHMARK(BM_FrameToState120)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// [heading] off: the difference to the rows above is the heading's share of the frame.
void BM_FrameToState64NoHeading(benchmark::State& state) {
  FrameToState(state, Variant::kBands64NoHeading);
}
BENCHMARK(BM_FrameToState64NoHeading)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

void BM_FrameToState120NoHeading(benchmark::State& state) {
  FrameToState(state, Variant::kBands120NoHeading);
}
BENCHMARK(BM_FrameToState120NoHeading)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// Reference: reading every byte of one frame.
void BM_ReadFrame(benchmark::State& state) {
  std::vector<std::uint8_t> image(static_cast<std::size_t>(kWidth) * kHeight, 7);
  for (auto _ : state) {
    const unsigned sum = std::accumulate(image.begin(), image.end(), 0u);
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_ReadFrame)->Unit(benchmark::kMicrosecond);

}  // namespace
