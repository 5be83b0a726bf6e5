#include "skyloc/sim/rendered_source.h"

#include <gtest/gtest.h>

#include <vector>

#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/platform/alloc_counter.h"

namespace skyloc::sim {
namespace {

class RenderedSourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(MakeProceduralWorld(WorldKind::kRepetitive, 1, &world_).ok());
    MotionConfig motion;
    motion.max_frames = 5;
    motion.bumps_deg = 5;
    ASSERT_TRUE(BuildTrajectory(world_.route, world_.route_closed, motion, &trajectory_).ok());
    config_.lens = DefaultSimLens(64, 48);
  }
  World world_;
  std::vector<TrajectoryPoint> trajectory_;
  RenderedSourceConfig config_;
  ManualClock clock_;
};

TEST_F(RenderedSourceTest, DeliversEveryPoseThenEndsWithOutOfRange) {
  RenderedSource source(&world_, trajectory_, config_);
  drivers::SimulatedCamera camera(source.camera_config(), &source, &clock_);
  ASSERT_TRUE(camera.Open().ok());
  EXPECT_STREQ(camera.info().name, "sim:repetitive:uv");
  EXPECT_EQ(camera.info().format, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(camera.Start().ok());
  for (std::size_t i = 0; i < trajectory_.size(); ++i) {
    Result<drivers::Frame> frame = camera.Capture(Nanoseconds{0});
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    EXPECT_EQ(frame->sequence, i);
    ASSERT_TRUE(frame->pose.has_value());
    EXPECT_EQ(frame->pose->x_m, trajectory_[i].pose.x_m);
    EXPECT_EQ(frame->pose->roll_deg, trajectory_[i].pose.roll_deg);
    EXPECT_EQ(frame->timestamp.count(), static_cast<std::int64_t>(i) * 100'000'000);
    EXPECT_EQ(frame->image.width, 64);
    // The frame is the renderer's image of that pose.
    std::vector<std::uint8_t> expected(64 * 48);
    ASSERT_TRUE(source.renderer()
                    .Render(trajectory_[i].pose, config_.lighting, Spectrum::kUv, i,
                            {expected.data(), 64, 48, 64, dsp::PixelFormat::kGrey8})
                    .ok());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), frame->image.data));
  }
  EXPECT_EQ(camera.Capture(Nanoseconds{0}).status().code(), StatusCode::kOutOfRange);
  EXPECT_EQ(camera.counters().frames, trajectory_.size());
  camera.Stop();
  camera.Close();
}

TEST_F(RenderedSourceTest, CaptureDoesNotAllocate) {
  ASSERT_TRUE(AllocationCounterActive());
  for (Spectrum s : {Spectrum::kUv, Spectrum::kVisible}) {
    config_.spectrum = s;
    RenderedSource source(&world_, trajectory_, config_);
    drivers::SimulatedCamera camera(source.camera_config(), &source, &clock_);
    ASSERT_TRUE(camera.Open().ok());
    ASSERT_TRUE(camera.Start().ok());
    AllocationScope scope;
    for (std::size_t i = 0; i < trajectory_.size(); ++i)
      ASSERT_TRUE(camera.Capture(Nanoseconds{0}).ok());
    EXPECT_EQ(scope.allocations(), 0u) << SpectrumName(s);
  }
}

}  // namespace
}  // namespace skyloc::sim
