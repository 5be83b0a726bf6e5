// The simulated status output's record: what changed, when, and what happens when the
// fixed history overflows. And StatusPattern's blink timing against hand-computed edges.
#include "skyloc/drivers/simulated_status_output.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "skyloc/drivers/status_pattern.h"
#include "skyloc/platform/clock.h"

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;

SimulatedStatusOutputConfig Config(StatusLineMode mode, std::size_t capacity) {
  SimulatedStatusOutputConfig c;
  c.mode = mode;
  c.history_capacity = capacity;
  return c;
}

TEST(SimulatedStatusOutput, RecordsOnlyChangesWithTheirTimes) {
  ManualClock clock(milliseconds(5));
  SimulatedStatusOutput out(Config(StatusLineMode::kLinePerState, 32), &clock);
  ASSERT_TRUE(out.Open().ok());
  // Open records the initial safe level of each line at the clock's time.
  ASSERT_EQ(out.history().size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(out.history()[i].time, milliseconds(5));
    EXPECT_FALSE(out.history()[i].level);
  }
  out.ClearHistory();
  ASSERT_TRUE(out.Show(LocalisationState::kSearching, 0.2f, milliseconds(10)).ok());
  ASSERT_TRUE(out.Show(LocalisationState::kSearching, 0.4f, milliseconds(20)).ok());  // no change
  ASSERT_TRUE(out.Show(LocalisationState::kLocalised, 0.9f, milliseconds(30)).ok());
  clock.Set(milliseconds(40));
  ASSERT_TRUE(out.SafeState().ok());
  const std::vector<LineChange> expected = {
      {milliseconds(10), 1, true},
      {milliseconds(30), 1, false},
      {milliseconds(30), 2, true},
      {milliseconds(40), 2, false},
  };
  ASSERT_EQ(out.history().size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(out.history()[i].time, expected[i].time) << i;
    EXPECT_EQ(out.history()[i].line, expected[i].line) << i;
    EXPECT_EQ(out.history()[i].level, expected[i].level) << i;
  }
  EXPECT_EQ(out.overwritten(), 0u);
}

TEST(SimulatedStatusOutput, FullHistoryKeepsTheNewestAndCountsTheLoss) {
  ManualClock clock;
  SimulatedStatusOutput out(Config(StatusLineMode::kBlink, 4), &clock);
  ASSERT_TRUE(out.Open().ok());  // 1 record
  // SEARCHING at 1 Hz sampled every 250 ms: an edge every 500 ms.
  for (int t = 0; t <= 3000; t += 250)
    ASSERT_TRUE(out.Show(LocalisationState::kSearching, 0.0f, milliseconds(t)).ok());
  // Edges at 0 (on), 500 (off), 1000, 1500, 2000, 2500, 3000: 7, plus the open record.
  EXPECT_EQ(out.history().size(), 4u);
  EXPECT_EQ(out.overwritten(), 4u);
  EXPECT_EQ(out.history().FromNewest(0).time, milliseconds(3000));
  EXPECT_TRUE(out.history().FromNewest(0).level);
  EXPECT_EQ(out.history()[0].time, milliseconds(1500));
}

TEST(SimulatedStatusOutput, CloseGoesSafeAndLinesReadOff) {
  ManualClock clock;
  SimulatedStatusOutput out(Config(StatusLineMode::kLinePerState, 8), &clock);
  ASSERT_TRUE(out.Open().ok());
  ASSERT_TRUE(out.Show(LocalisationState::kLocalised, 1.0f, milliseconds(1)).ok());
  EXPECT_TRUE(out.Level(2));
  clock.Set(milliseconds(7));
  out.Close();
  EXPECT_FALSE(out.Level(2));
  EXPECT_EQ(out.history().FromNewest(0).time, milliseconds(7));
  EXPECT_FALSE(out.history().FromNewest(0).level);
}

TEST(SimulatedStatusOutput, ButtonWithoutConfigurationIsAnError) {
  ManualClock clock;
  SimulatedStatusOutput out(Config(StatusLineMode::kBlink, 8), &clock);
  ASSERT_TRUE(out.Open().ok());
  EXPECT_EQ(out.button_event_fd(), -1);
  EXPECT_EQ(out.ButtonPressed().status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(out.ReadButtonEvent().status().code(), StatusCode::kFailedPrecondition);
}

TEST(StatusPattern, BlinkEdgesOverTime) {
  // Sampling every millisecond, the LOCALISED line at confidence 1 (10 Hz) must change
  // exactly 20 times a second, and be on for exactly half the samples.
  const StatusPattern pattern(StatusLineMode::kBlink);
  int edges = 0, on = 0;
  bool last = pattern.Levels(LocalisationState::kLocalised, 1.0f, milliseconds(0)).level[0];
  for (int t = 1; t <= 1000; ++t) {
    const bool now = pattern.Levels(LocalisationState::kLocalised, 1.0f, milliseconds(t)).level[0];
    edges += now != last;
    on += now;
    last = now;
  }
  EXPECT_EQ(edges, 20);
  EXPECT_EQ(on, 500);
}

TEST(StatusPattern, ConfidenceIsClampedAndNanIsTreatedAsZero) {
  const auto slow = StatusPattern::BlinkFor(LocalisationState::kLocalised, 0.0f);
  const auto fast = StatusPattern::BlinkFor(LocalisationState::kLocalised, 1.0f);
  EXPECT_EQ(slow.period, milliseconds(500));
  EXPECT_EQ(fast.period, milliseconds(100));
  EXPECT_EQ(StatusPattern::BlinkFor(LocalisationState::kLocalised, -3.0f).period, slow.period);
  EXPECT_EQ(StatusPattern::BlinkFor(LocalisationState::kLocalised, 7.0f).period, fast.period);
  EXPECT_EQ(StatusPattern::BlinkFor(LocalisationState::kLocalised,
                                    std::numeric_limits<float>::quiet_NaN())
                .period,
            slow.period);
}

// NextEdge() against the pattern itself, sampled every 0.5 ms: from any time, the edge it
// names is the first sample at which Levels() differs, for every state and a spread of
// confidences (the LOCALISED periods are whole microseconds, not milliseconds).
TEST(StatusPattern, NextEdgeIsTheFirstChangeOfTheLevel) {
  const StatusPattern pattern(StatusLineMode::kBlink);
  using std::chrono::microseconds;
  struct Case {
    LocalisationState state;
    float confidence;
  };
  const Case cases[] = {{LocalisationState::kLost, 0.0f},
                        {LocalisationState::kSearching, 0.5f},
                        {LocalisationState::kLocalised, 0.0f},
                        {LocalisationState::kLocalised, 0.37f},
                        {LocalisationState::kLocalised, 1.0f}};
  for (const Case& c : cases) {
    for (Nanoseconds t = milliseconds(3000); t < milliseconds(5500); t += microseconds(12'345)) {
      const bool level = pattern.Levels(c.state, c.confidence, t).level[0];
      const Nanoseconds edge = pattern.NextEdge(c.state, c.confidence, t);
      ASSERT_GT(edge, t);
      // Unchanged up to just before the edge, changed at it.
      EXPECT_EQ(pattern.Levels(c.state, c.confidence, edge - Nanoseconds(1)).level[0], level)
          << LocalisationStateName(c.state) << " c=" << c.confidence << " t=" << t.count();
      EXPECT_NE(pattern.Levels(c.state, c.confidence, edge).level[0], level)
          << LocalisationStateName(c.state) << " c=" << c.confidence << " t=" << t.count();
      for (Nanoseconds u = t; u < edge; u += microseconds(500))
        ASSERT_EQ(pattern.Levels(c.state, c.confidence, u).level[0], level) << u.count();
    }
  }
  // One line per state never changes by itself.
  const StatusPattern per_state(StatusLineMode::kLinePerState);
  EXPECT_EQ(per_state.NextEdge(LocalisationState::kLocalised, 1.0f, milliseconds(7)),
            Nanoseconds::max());
}

TEST(StatusPattern, ParsesModeNames) {
  ASSERT_TRUE(ParseStatusLineMode("blink").ok());
  EXPECT_EQ(*ParseStatusLineMode("blink"), StatusLineMode::kBlink);
  EXPECT_EQ(*ParseStatusLineMode("per-state"), StatusLineMode::kLinePerState);
  const auto bad = ParseStatusLineMode("strobe");
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(bad.status().message()).find("strobe"), std::string::npos);
}

}  // namespace
}  // namespace skyloc::drivers
