// Every path that describes a frame builds its descriptor from the configuration through
// firmware::SkyDescriptorOptionsFrom: the robot's pipeline, `skyloc eval`, `skyloc describe`
// and the experiments. Here the same simulated UV frames go through all four and must give
// the same float bits, for the robot's default descriptor and for one that changes every
// setting the factory reads (a fixed segmentation threshold, 64 bands on the "auto" grid,
// no normalisation, the gravity-aligned cap from [attitude]). A path that dropped or
// rebuilt any of those settings would give other bits.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "cli/describe.h"
#include "firmware/config.h"
#include "firmware/pipeline.h"
#include "skyloc/platform/clock.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"
#include "support/scratch_dir.h"
#include "tools/eval_describe.h"
#include "tools/experiment.h"

namespace skyloc {
namespace {

constexpr int kWidth = 96;
constexpr int kHeight = 72;
constexpr int kFrames = 4;

// The simulator's lens (sim::DefaultSimLens) as a camera file, so the pipeline reads the
// frames through the lens they were rendered with.
std::string WriteSimCameraFile(const std::string& dir) {
  const dsp::LensParams lens = sim::DefaultSimLens(kWidth, kHeight);
  const std::string path = dir + "/camera.toml";
  std::FILE* f = std::fopen(path.c_str(), "w");
  EXPECT_NE(f, nullptr) << path;
  if (f == nullptr)
    return path;
  std::fprintf(f,
               "[image]\nwidth = %d\nheight = %d\n\n[lens]\nmodel = \"equidistant\"\n"
               "fov_deg = %.17g\n\n[mount]\nroll_deg = %.17g\npitch_deg = %.17g\n"
               "yaw_deg = %.17g\n",
               lens.width, lens.height, lens.fov_deg, lens.roll_deg, lens.pitch_deg, lens.yaw_deg);
  std::fclose(f);
  return path;
}

struct Case {
  const char* name;
  firmware::Config config;
  bool attitude;  // the gravity-aligned cap, each frame levelled by its true attitude
};

std::vector<Case> Cases(const std::string& camera_file) {
  firmware::Config robot = firmware::DefaultConfig();
  robot.camera.capture.width = kWidth;
  robot.camera.capture.height = kHeight;
  robot.camera.lens_file = camera_file;
  firmware::Config changed = robot;
  changed.segmentation.method = firmware::SegmentationMethod::kFixed;
  changed.segmentation.threshold = 90;
  changed.descriptor.bands = 64;  // not the default's 120
  changed.descriptor.grid = firmware::GridPreset::kAuto;
  changed.descriptor.normalisation = dsp::AmplitudeNormalisation::kNone;
  firmware::ResolveDescriptorGrid(&changed.descriptor);
  changed.attitude.kind = firmware::AttitudeKind::kSim;
  changed.attitude.max_tilt_deg = 22;
  changed.attitude.cap_taper_deg = 7;
  return {{"robot's default", robot, false}, {"every setting changed", changed, true}};
}

bool SameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(SameDescriptor, PipelineEvalDescribeAndExperimentsGiveTheSameBits) {
  const testing::ScratchDir scratch("same_descriptor_");
  ASSERT_FALSE(scratch.path().empty());
  const std::string camera_file = WriteSimCameraFile(scratch.path());
  sim::World world;
  ASSERT_TRUE(sim::MakeProceduralWorld(sim::WorldKind::kCity, 1, &world).ok());
  tools::RunSpec spec;
  spec.label = "tilted";
  spec.motion.tilt_deg = 12;
  spec.motion.bumps_deg = 6;
  ASSERT_TRUE(sim::LightingPreset("noon", 7, &spec.lighting));
  sim::Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, sim::DefaultSimLens(kWidth, kHeight)).ok());

  for (const Case& c : Cases(camera_file)) {
    SCOPED_TRACE(c.name);
    // (d) The experiments: DescribeRun renders the run and describes every frame.
    tools::ExperimentOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.max_frames = kFrames;
    options.vanilla = false;
    options.config = c.config;
    options.attitude = c.attitude ? tools::AttitudeInput::kTruth : tools::AttitudeInput::kNone;
    options.cap = c.attitude;
    tools::RunDescriptors run;
    Status s = tools::DescribeRun(world, world.route, world.route_closed, spec, options, &run);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(run.trajectory.size(), static_cast<std::size_t>(kFrames));
    const int bands = c.config.descriptor.bands;
    const auto dim = static_cast<std::size_t>(bands);

    // (a) The robot's pipeline, its lens from the configuration's camera file.
    ManualClock clock;
    firmware::Pipeline pipeline(clock);
    s = pipeline.Init(c.config);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(pipeline.dim(), bands);
    ASSERT_EQ(pipeline.uses_attitude(), c.attitude);
    // (b) eval and (c) describe, through the lens the frames were rendered with.
    const dsp::Lens& lens = renderer.lens();
    dsp::SkyDescriptor eval;
    tools::DescribeSettings eval_settings;
    eval_settings.config = c.config;
    eval_settings.attitude_from_dataset = c.attitude;
    ASSERT_TRUE(eval.Init(lens, tools::EvalSkyDescriptorOptions(eval_settings, lens)).ok());
    dsp::SkyDescriptor describe;
    s = cli::InitDescribeDescriptor(cli::DescribeConfig(c.config, {}), lens, &describe);
    ASSERT_TRUE(s.ok()) << s.message();

    std::vector<std::uint8_t> uv(static_cast<std::size_t>(kWidth * kHeight));
    const dsp::MutableImageView view{uv.data(), kWidth, kHeight, kWidth, dsp::PixelFormat::kGrey8};
    for (std::size_t i = 0; i < run.trajectory.size(); ++i) {
      SCOPED_TRACE(i);
      ASSERT_TRUE(
          renderer.Render(run.trajectory[i].pose, spec.lighting, sim::Spectrum::kUv, i, view).ok());
      const dsp::Attitude* attitude = c.attitude ? &run.attitude[i] : nullptr;
      const std::vector<float>& experiment_all = c.attitude ? run.sky_cap : run.sky;
      const std::vector<float> experiment(
          experiment_all.begin() + static_cast<long>(i * dim),
          experiment_all.begin() + static_cast<long>((i + 1) * dim));
      firmware::FrameResult result;
      s = pipeline.Describe(view, &result, attitude);
      ASSERT_TRUE(s.ok()) << s.message();
      const std::vector<float> robot(pipeline.descriptor().begin(), pipeline.descriptor().end());
      std::vector<float> by_eval(dim), by_describe(dim);
      ASSERT_TRUE(eval.Compute(view, by_eval, nullptr, attitude).ok());
      ASSERT_TRUE(describe.Compute(view, by_describe, nullptr, attitude).ok());
      EXPECT_TRUE(SameBits(robot, by_eval)) << "eval differs from the pipeline";
      EXPECT_TRUE(SameBits(robot, by_describe)) << "describe differs from the pipeline";
      EXPECT_TRUE(SameBits(robot, experiment)) << "the experiment differs from the pipeline";
    }
  }
}

// The comparison above can tell descriptors apart: the two cases' settings give other
// bits on the same frame (so a path that dropped them would be caught).
TEST(SameDescriptor, TheSettingsChangeTheBits) {
  const testing::ScratchDir scratch("same_descriptor_");
  ASSERT_FALSE(scratch.path().empty());
  const std::vector<Case> cases = Cases(WriteSimCameraFile(scratch.path()));
  sim::World world;
  ASSERT_TRUE(sim::MakeProceduralWorld(sim::WorldKind::kCity, 1, &world).ok());
  sim::Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, sim::DefaultSimLens(kWidth, kHeight)).ok());
  std::vector<std::uint8_t> uv(static_cast<std::size_t>(kWidth * kHeight));
  const dsp::MutableImageView view{uv.data(), kWidth, kHeight, kWidth, dsp::PixelFormat::kGrey8};
  sim::Lighting noon;
  ASSERT_TRUE(sim::LightingPreset("noon", 7, &noon));
  drivers::Pose pose;
  pose.x_m = world.route.front().x;
  pose.y_m = world.route.front().y;
  pose.z_m = 1.0;
  pose.pitch_deg = 12;
  ASSERT_TRUE(renderer.Render(pose, noon, sim::Spectrum::kUv, 0, view).ok());
  // Each setting alone, on the robot's descriptor with 64 bands: every setting changes the
  // bits at any band count, and fewer bands keep the five descriptors quick under qemu-user.
  firmware::Config robot = cases[0].config;
  robot.descriptor.bands = 64;
  firmware::ResolveDescriptorGrid(&robot.descriptor);
  std::vector<firmware::Config> variants(4, robot);
  variants[0].segmentation.method = firmware::SegmentationMethod::kFixed;
  variants[0].segmentation.threshold = 90;
  variants[1].descriptor.grid = firmware::GridPreset::kAuto;
  firmware::ResolveDescriptorGrid(&variants[1].descriptor);
  variants[2].descriptor.normalisation = dsp::AmplitudeNormalisation::kNone;
  variants[3].attitude.kind = firmware::AttitudeKind::kSim;
  const auto describe = [&](const firmware::Config& config) {
    dsp::SkyDescriptor d;
    EXPECT_TRUE(cli::InitDescribeDescriptor(config, renderer.lens(), &d).ok());
    std::vector<float> a(static_cast<std::size_t>(config.descriptor.bands));
    EXPECT_TRUE(d.Compute(view, a).ok());
    return a;
  };
  const std::vector<float> base = describe(robot);
  for (std::size_t k = 0; k < variants.size(); ++k)
    EXPECT_FALSE(SameBits(base, describe(variants[k]))) << "variant " << k;
}

}  // namespace
}  // namespace skyloc
