// The teach button through the frame loop, with the simulated status output's button and
// a ManualClock (the camera advances it one frame period per capture, so debouncing is
// exact): repeat without a route waits for a press, teaches until the next one, commits
// and repeats on the new route; the old route is untouched until the commit; the button
// path allocates nothing per frame.
#include "firmware/button_teach.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/street_source.h"
#include "small_config.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

constexpr Nanoseconds kFramePeriod = std::chrono::milliseconds(33);

using testing::SmallConfig;
using testing::SmallStreet;

// Two drives along the same street: the first until capture `second_from`, then another
// from the start (so a route taught on the first is repeated on the second). Each capture
// advances the clock by one frame period and then runs the test's script for that call.
class ScriptedCamera final : public drivers::Camera {
 public:
  ScriptedCamera(ManualClock* clock, std::uint64_t second_from,
                 std::function<void(std::uint64_t)> script)
      : first_(SmallStreet(1)),
        second_(SmallStreet(2)),
        clock_(clock),
        second_from_(second_from),
        script_(std::move(script)) {}
  std::uint64_t calls() const { return calls_; }

 private:
  Status DoOpen() override {
    SKYLOC_TRY(first_.camera.Open());
    SKYLOC_TRY(second_.camera.Open());
    info_ = first_.camera.info();
    return Status::Ok();
  }
  Status DoStart() override {
    SKYLOC_TRY(first_.camera.Start());
    return second_.camera.Start();
  }
  Result<drivers::Frame> DoCapture(Nanoseconds timeout) override {
    const std::uint64_t call = calls_++;
    clock_->Advance(kFramePeriod);
    script_(call);
    return call < second_from_ ? first_.camera.Capture(timeout) : second_.camera.Capture(timeout);
  }
  void DoStop() override {
    first_.camera.Stop();
    second_.camera.Stop();
  }
  void DoClose() override {
    first_.camera.Close();
    second_.camera.Close();
  }

  sim::FilmedStreet first_, second_;
  ManualClock* clock_;
  std::uint64_t second_from_;
  std::function<void(std::uint64_t)> script_;
  std::uint64_t calls_ = 0;
};

class ButtonTeach : public ::testing::Test {
 protected:
  void SetUp() override {
    ClearSignalFlags();
    ASSERT_TRUE(pipeline_.Init(SmallConfig()).ok());
    ASSERT_TRUE(route_.Allocate(400, static_cast<std::size_t>(pipeline_.dim())).ok());
    drivers::SimulatedStatusOutputConfig c;
    c.has_button = true;
    c.history_capacity = 4096;
    status_ = std::make_unique<drivers::SimulatedStatusOutput>(c, &clock_);
    ASSERT_TRUE(status_->Open().ok());
  }
  void TearDown() override {
    status_->Close();
    ClearSignalFlags();
  }

  ButtonTeachSetup Setup(drivers::Camera* camera) {
    ButtonTeachSetup s;
    s.camera = camera;
    s.status = status_.get();
    s.pipeline = &pipeline_;
    s.route = &route_;
    s.route_path = path_.c_str();
    s.flush_every = 25;
    return s;
  }
  LoopOptions Options() {
    return LoopOptions{};  // the loop's clock is the pipeline's, clock_
  }
  // Opens and starts the camera and runs repeat with a 50 ms debounced button until the
  // camera's script requests a stop.
  ::testing::AssertionResult RunUntilStopped(drivers::Camera* camera, ButtonTeachReport* report) {
    if (!camera->Open().ok() || !camera->Start().ok())
      return ::testing::AssertionFailure() << "the scripted camera did not open and start";
    ButtonDebouncer button(std::chrono::milliseconds(50));
    const Status s = RunRepeatWithButton(Setup(camera), Options(), &button, report);
    if (!s.ok())
      return ::testing::AssertionFailure() << s.message();
    return ::testing::AssertionSuccess();
  }
  // Changes of the SEARCHING line (per-state line 1) in the history.
  int SearchingChanges() const {
    int n = 0;
    const auto& h = status_->history();
    for (std::size_t i = 0; i < h.size(); ++i)
      n += h[i].line == 1 ? 1 : 0;
    return n;
  }

  ManualClock clock_{std::chrono::seconds(1)};
  Pipeline pipeline_{clock_};
  RouteFrames route_;
  std::unique_ptr<drivers::SimulatedStatusOutput> status_;
  const skyloc::testing::ScratchDir scratch_{"skyloc_button_"};
  const std::string path_ = scratch_.path() + "/route.db";
};

TEST_F(ButtonTeach, WaitsForAPressTeachesUntilTheNextAndRepeatsOnTheNewRoute) {
  // Frame 5: pressed (bouncing for one frame), accepted 50 ms later, released at 10;
  // frame 130 pressed again, released 134: the teach ends. Then the second drive.
  ScriptedCamera camera(&clock_, 140, [&](std::uint64_t call) {
    if (call == 5 || call == 6 || call == 130)
      status_->PressButton();
    if (call == 5 || call == 10 || call == 134)
      status_->ReleaseButton();
    if (call == 60) {  // mid-teach: nothing at the route's path is a route yet
      RouteFrames probe;
      ASSERT_TRUE(probe.Allocate(400, static_cast<std::size_t>(pipeline_.dim())).ok());
      const RouteDbSettings want = pipeline_.route_settings();
      EXPECT_FALSE(
          LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &probe, nullptr).ok());
    }
    if (call == 140) {  // taught: captures 9..132 (see below), loaded for the repeat
      EXPECT_EQ(route_.size(), 124u);
    }
    if (call == 300)
      RequestStop();
  });
  ButtonTeachReport report;
  ASSERT_TRUE(RunUntilStopped(&camera, &report));
  EXPECT_EQ(report.routes_taught, 1u);
  EXPECT_TRUE(report.loop.stopped);
  // Edges are read before each capture, at the clock of the previous one. Waiting:
  // captures 0..8 (the press at capture 6 is 66 ms old before capture 9). Teaching:
  // captures 9..132 (the press at 130 is accepted before capture 133).
  ASSERT_GT(route_.size(), 100u);
  EXPECT_LT(route_.size(), 130u);
  // The route on the disk is the one loaded, and no unfinished file is left.
  RouteFrames loaded;
  ASSERT_TRUE(loaded.Allocate(400, static_cast<std::size_t>(pipeline_.dim())).ok());
  const RouteDbSettings want = pipeline_.route_settings();
  ASSERT_TRUE(LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &loaded, nullptr).ok());
  EXPECT_EQ(loaded.size(), route_.size());
  EXPECT_FALSE(std::filesystem::exists(path_ + ".tmp"));
  // While teaching (about 4 s), the SEARCHING line blinked at 0.5 Hz: on and off a few times.
  EXPECT_GE(SearchingChanges(), 4);
  // The second drive along the street localised on the new route.
  EXPECT_GT(report.loop.state_frames[static_cast<int>(dsp::LocalisationState::kLocalised)], 50u);
}

TEST_F(ButtonTeach, TheOldRouteIsKeptUntilTheNewOneIsCommitted) {
  // An old route of 40 frames.
  {
    RouteDbWriter old;
    ASSERT_TRUE(old.Create(path_.c_str(), pipeline_.route_settings(), 25, false).ok());
    sim::FilmedStreet filmed(SmallStreet(1));
    drivers::Camera& street = filmed.camera;
    ASSERT_TRUE(street.Open().ok());
    ASSERT_TRUE(street.Start().ok());
    LoopOptions o;
    o.mode = LoopMode::kTeach;
    o.max_frames = 40;
    LoopSummary summary;
    ASSERT_TRUE(RunFrameLoop(street, nullptr, pipeline_, &old, nullptr, o, &summary).ok());
    ASSERT_TRUE(old.Commit().ok());
  }
  const RouteDbSettings want = pipeline_.route_settings();
  ASSERT_TRUE(LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &route_, nullptr).ok());
  ASSERT_TRUE(pipeline_.SetRoute(route_).ok());
  ASSERT_EQ(route_.size(), 40u);

  ScriptedCamera camera(&clock_, 1000, [&](std::uint64_t call) {
    if (call == 20 || call == 100)
      status_->PressButton();
    if (call == 25 || call == 105)
      status_->ReleaseButton();
    if (call == 60) {  // mid-teach: the old route still loads whole; the new one is in .tmp
      RouteFrames probe;
      ASSERT_TRUE(probe.Allocate(400, static_cast<std::size_t>(pipeline_.dim())).ok());
      ASSERT_TRUE(
          LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &probe, nullptr).ok());
      EXPECT_EQ(probe.size(), 40u);
      EXPECT_TRUE(std::filesystem::exists(path_ + ".tmp"));
    }
    if (call == 150)
      RequestStop();
  });
  ButtonTeachReport report;
  ASSERT_TRUE(RunUntilStopped(&camera, &report));
  EXPECT_EQ(report.routes_taught, 1u);
  EXPECT_EQ(route_.size(), 80u);  // captures 23..102
  EXPECT_FALSE(std::filesystem::exists(path_ + ".tmp"));
}

TEST_F(ButtonTeach, RepeatWithTheButtonPolledAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  RouteFrames taught;
  {
    sim::FilmedStreet filmed(SmallStreet(1));
    drivers::Camera& street = filmed.camera;
    ASSERT_TRUE(street.Open().ok());
    ASSERT_TRUE(street.Start().ok());
    for (int i = 0; i < 200; ++i) {
      Result<drivers::Frame> f = street.Capture(std::chrono::seconds(1));
      ASSERT_TRUE(f.ok());
      FrameResult r;
      ASSERT_TRUE(pipeline_.Describe(f->image, &r).ok());
      if (route_.size() < route_.capacity()) {
        ASSERT_TRUE(route_.Append(RouteFrameMeta{}, pipeline_.descriptor()));
      }
    }
  }
  ASSERT_TRUE(pipeline_.SetRoute(route_).ok());
  sim::FilmedStreet filmed(SmallStreet(2));
  drivers::Camera& camera = filmed.camera;
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  ButtonDebouncer button(std::chrono::milliseconds(50));
  LoopOptions o = Options();
  o.button = &button;
  o.max_frames = 10;
  LoopSummary summary;
  ASSERT_TRUE(RunFrameLoop(camera, status_.get(), pipeline_, nullptr, nullptr, o, &summary).ok());
  o.max_frames = 1000;
  status_->PressButton();  // an edge to read, but never held long enough by the clock
  status_->ReleaseButton();
  AllocationScope scope;
  const Status s = RunFrameLoop(camera, status_.get(), pipeline_, nullptr, nullptr, o, &summary);
  const std::uint64_t allocations = scope.allocations();
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(summary.frames, 1000u);
  EXPECT_FALSE(summary.button_pressed);
}

TEST_F(ButtonTeach, TeachingWithTheButtonAndItsPatternAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  RouteDbWriter writer;
  ASSERT_TRUE(writer.Create(path_.c_str(), pipeline_.route_settings(), 25, false).ok());
  sim::FilmedStreet filmed(SmallStreet(1));
  drivers::Camera& camera = filmed.camera;
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  ButtonDebouncer button(std::chrono::milliseconds(50));
  LoopOptions o = Options();
  o.mode = LoopMode::kTeach;
  o.button = &button;
  o.show_teaching = true;
  o.max_frames = 10;
  LoopSummary summary;
  ASSERT_TRUE(RunFrameLoop(camera, status_.get(), pipeline_, &writer, nullptr, o, &summary).ok());
  o.max_frames = 300;
  // The ManualClock stands still, so the pattern is checked at both halves of its period.
  AllocationScope scope;
  Status s = RunFrameLoop(camera, status_.get(), pipeline_, &writer, nullptr, o, &summary);
  clock_.Advance(kTeachingPeriod / 2);
  if (s.ok())
    s = RunFrameLoop(camera, status_.get(), pipeline_, &writer, nullptr, o, &summary);
  const std::uint64_t allocations = scope.allocations();
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(allocations, 0u);
  ASSERT_TRUE(writer.Commit().ok());
}

}  // namespace
}  // namespace skyloc::firmware
