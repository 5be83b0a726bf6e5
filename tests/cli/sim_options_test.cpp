// The options of a simulated run (AddSimRunOptions): teach/repeat/record take the run's,
// `skyloc simulate` also the world's and the sampling's; each fills its field of the one
// SimRunConfig, and a value out of range is refused naming the option.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "firmware/config.h"
#include "support/command_line.h"

namespace skyloc::cli {
namespace {

using Args = skyloc::testing::CommandLine;

TEST(SimRunOptions, TheRunsOptionsFillTheRun) {
  firmware::SimRunConfig run;
  OptionTable t("teach", "[options]", "");
  AddSimRunOptions(&t, SimRunOptions::kRun, &run);
  const Args a({"--tilt", "-12.5", "--zigzag", "30", "--bumps", "4", "--yaw", "135", "--lighting",
                "overcast", "--run", "17"});
  ASSERT_EQ(t.Parse(a.span()), ParseOutcome::kRun);
  EXPECT_EQ(run.ride.tilt_deg, -12.5);
  EXPECT_EQ(run.ride.zigzag_deg, 30.0);
  EXPECT_EQ(run.ride.bumps_deg, 4.0);
  EXPECT_EQ(run.ride.yaw_offset_deg, 135.0);
  EXPECT_EQ(run.lighting, "overcast");
  EXPECT_EQ(run.ride.seed, 17u);
  // The world is the configuration's: teach has no --world.
  EXPECT_EQ(run.world, firmware::SimRunConfig{}.world);
}

TEST(SimRunOptions, TeachRefusesTheWorldsOptions) {
  firmware::SimRunConfig run;
  OptionTable t("teach", "[options]", "");
  AddSimRunOptions(&t, SimRunOptions::kRun, &run);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(t.Parse(Args({"--spacing", "2"}).span()), ParseOutcome::kRefused);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("unknown option '--spacing'"),
            std::string::npos);
}

TEST(SimRunOptions, SimulateFillsTheWorldAndTheSampling) {
  firmware::SimRunConfig run;
  OptionTable t("simulate", "[options]", "");
  AddSimRunOptions(&t, SimRunOptions::kWorldAndRun, &run);
  const Args a({"--world", "repetitive", "--seed", "4", "--speed", "2.5", "--speed-band", "0.1",
                "--accel", "1.5", "--start-stop", "0", "--stops", "3", "--stop-seconds", "1,4",
                "--camera-height", "0.5"});
  ASSERT_EQ(t.Parse(a.span()), ParseOutcome::kRun);
  EXPECT_EQ(run.world.name, "repetitive");
  EXPECT_EQ(run.world.seed, 4u);
  EXPECT_EQ(run.world.frames.speed.cruise_mps, 2.5);
  EXPECT_EQ(run.world.frames.speed.band, 0.1);
  EXPECT_EQ(run.world.frames.speed.accel_mps2, 1.5);
  EXPECT_EQ(run.world.frames.speed.start_stop_s, 0.0);
  EXPECT_EQ(run.world.frames.speed.stops, 3);
  EXPECT_EQ(run.world.frames.speed.stop_min_s, 1.0);
  EXPECT_EQ(run.world.frames.speed.stop_max_s, 4.0);
  EXPECT_EQ(run.ride.height_m, 0.5);

  firmware::SimRunConfig distance;
  OptionTable d("simulate", "[options]", "");
  AddSimRunOptions(&d, SimRunOptions::kWorldAndRun, &distance);
  ASSERT_EQ(d.Parse(Args({"--spacing", "0.05", "--jitter", "0.3"}).span()), ParseOutcome::kRun);
  EXPECT_EQ(distance.world.frames.frame_spacing_m, 0.05);
  EXPECT_EQ(distance.world.frames.speed_jitter, 0.3);
}

TEST(SimRunOptions, RefusesOutOfRangeNamingTheOptionAndWhatIsExpected) {
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const Case cases[] = {
      {{"--tilt", "91"}, "--tilt '91': expected a number in [-90, 90]"},
      {{"--bumps", "-1"}, "--bumps '-1': expected a number in [0, 45]"},
      {{"--zigzag", "181"}, "--zigzag '181': expected a number in [-180, 180]"},
      {{"--lighting", "dusk"}, "--lighting 'dusk': expected dawn, noon or overcast"},
      {{"--run", "-1"}, "--run '-1': expected a whole number >= 0"},
      {{"--world", "moon"}, "--world 'moon': expected seville, city, forest or repetitive"},
      {{"--stop-seconds", "5,2"}, "--stop-seconds '5,2': expected MIN,MAX seconds"},
      {{"--stop-seconds", "2"}, "--stop-seconds '2': expected MIN,MAX seconds"},
      {{"--jitter", "1"}, "--jitter '1': expected a number in [0, 1)"},
      {{"--speed", "0"}, "--speed '0': expected a number in (0, 100]"},
      {{"--spacing", "0"}, "--spacing '0': expected a number > 0"},
  };
  for (const Case& c : cases) {
    firmware::SimRunConfig run;
    OptionTable t("simulate", "[options]", "");
    AddSimRunOptions(&t, SimRunOptions::kWorldAndRun, &run);
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(t.Parse(Args(c.args).span()), ParseOutcome::kRefused) << c.args[0];
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("skyloc simulate: " + c.expected), std::string::npos) << err;
    EXPECT_EQ(run, firmware::SimRunConfig{}) << c.args[0];
  }
}

TEST(OptionTable, NumberPairAndTextList) {
  double lo = -1, hi = -1;
  std::vector<std::string> dirs;
  OptionTable t("test", "[options]", "");
  t.NumberPair(
      "--range", "A,B", "a range", "A,B with A <= B", [](double a, double b) { return a <= b; },
      &lo, &hi);
  t.TextList("--train", "DIR", "training runs", &dirs);
  ASSERT_EQ(t.Parse(Args({"--range", "-2.5,1e1", "--train", "a", "--train", "b"}).span()),
            ParseOutcome::kRun);
  EXPECT_EQ(lo, -2.5);
  EXPECT_EQ(hi, 10.0);
  EXPECT_EQ(dirs, (std::vector<std::string>{"a", "b"}));
  for (const char* bad : {"3,2", "1,", ",1", "1;2", "1,2,3", "nan,1", "x,1"}) {
    OptionTable u("test", "[options]", "");
    u.NumberPair(
        "--range", "A,B", "a range", "A,B with A <= B", [](double a, double b) { return a <= b; },
        &lo, &hi);
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(u.Parse(Args({"--range", bad}).span()), ParseOutcome::kRefused) << bad;
    EXPECT_NE(::testing::internal::GetCapturedStderr().find("expected A,B with A <= B"),
              std::string::npos)
        << bad;
  }
}

}  // namespace
}  // namespace skyloc::cli
