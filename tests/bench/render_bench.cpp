// Simulator speed: one rendered frame per world, spectrum and size (docs/SIMULATOR.md
// quotes these), and BVH ray queries against the brute-force reference in the same run.
#include <benchmark/benchmark.h>

#include <vector>

#include "skyloc/sim/motion.h"
#include "skyloc/sim/random.h"
#include "skyloc/sim/renderer.h"

namespace {

using namespace skyloc;

const sim::World& WorldOf(sim::WorldKind kind) {
  static sim::World worlds[3];
  static bool built[3] = {};
  const int i = kind == sim::WorldKind::kCity ? 0 : kind == sim::WorldKind::kForest ? 1 : 2;
  if (!built[i]) {
    if (!sim::MakeProceduralWorld(kind, 1, &worlds[i]).ok())
      std::abort();
    built[i] = true;
  }
  return worlds[i];
}

void BM_Render(benchmark::State& state) {
  const auto kind = static_cast<sim::WorldKind>(state.range(0));
  const auto spectrum = static_cast<sim::Spectrum>(state.range(1));
  const int width = static_cast<int>(state.range(2)), height = width * 3 / 4;
  const sim::World& world = WorldOf(kind);
  sim::Renderer renderer;
  if (!renderer.Init(&world, sim::DefaultSimLens(width, height)).ok())
    std::abort();
  sim::MotionConfig motion;
  std::vector<sim::TrajectoryPoint> trajectory;
  if (!sim::BuildTrajectory(world.route, world.route_closed, motion, &trajectory).ok())
    std::abort();
  const int channels = spectrum == sim::Spectrum::kUv ? 1 : 3;
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width * height * channels));
  const dsp::MutableImageView out{
      pixels.data(), width, height, static_cast<std::size_t>(width * channels),
      spectrum == sim::Spectrum::kUv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24};
  sim::Lighting lighting;
  sim::LightingPreset("noon", 1, &lighting);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& pose = trajectory[(i * 37) % trajectory.size()].pose;
    if (!renderer.Render(pose, lighting, spectrum, i, out).ok())
      std::abort();
    ++i;
  }
  state.SetLabel(std::string(sim::WorldKindName(kind)) + " " + sim::SpectrumName(spectrum));
}
BENCHMARK(BM_Render)->ArgsProduct({{1, 2, 3}, {0, 1}, {320, 640}})->Unit(benchmark::kMillisecond);

// Closest-hit queries on the forest world: BVH vs every triangle (the reference).
void RayQueries(benchmark::State& state, bool brute_force) {
  const sim::World& world = WorldOf(sim::WorldKind::kForest);
  sim::Rng rng(3);
  std::vector<sim::Ray> rays;
  for (int k = 0; k < 64; ++k) {
    const auto& p = world.route[static_cast<std::size_t>(k) % world.route.size()];
    rays.push_back({{static_cast<float>(p.x), static_cast<float>(p.y), 1.0f},
                    {static_cast<float>(rng.Uniform(-1, 1)), static_cast<float>(rng.Uniform(-1, 1)),
                     static_cast<float>(rng.Uniform(0, 1))}});
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const sim::Ray& ray = rays[i++ % rays.size()];
    const sim::Hit hit = brute_force
                             ? sim::ClosestHitBruteForce(world.triangles(), ray, 1e-4f, 1e9f)
                             : world.bvh().ClosestHit(ray, 1e-4f, 1e9f);
    benchmark::DoNotOptimize(hit);
  }
}
void BM_ClosestHitBvh(benchmark::State& state) {
  RayQueries(state, false);
}
void BM_ClosestHitBruteForce(benchmark::State& state) {
  RayQueries(state, true);
}
BENCHMARK(BM_ClosestHitBvh);
BENCHMARK(BM_ClosestHitBruteForce);

}  // namespace
