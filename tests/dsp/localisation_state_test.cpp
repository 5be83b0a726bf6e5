// The state machine against hand-written sequences: each row is one frame's match and the
// state the rules in docs/STATE_MACHINE.md give for it, worked out by hand.
#include "skyloc/dsp/localisation_state.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace skyloc::dsp {
namespace {

// Small counts so the sequences stay readable: confirm 3, drop 2, lost 3; velocity band
// 0.8..1.2 route frames per frame with 1 frame of slack.
StateMachineParams Params() {
  StateMachineParams p;
  p.enter_confidence = 0.5f;
  p.stay_confidence = 0.3f;
  p.max_uniqueness = 0.9f;
  p.confirm_frames = 3;
  p.drop_frames = 2;
  p.lost_frames = 3;
  p.vmin = 0.8;
  p.vmax = 1.2;
  p.index_tolerance = 1.0;
  return p;
}

struct Step {
  std::int64_t index;
  float confidence;
  char expect;  // L = LOST, S = SEARCHING, K = LOCALISED (K for "known")
  float uniqueness = 0.5f;
  std::uint64_t frame_gap = 1;
};

char Letter(LocalisationState s) {
  return s == LocalisationState::kLost ? 'L' : s == LocalisationState::kSearching ? 'S' : 'K';
}

void Expect(const std::vector<Step>& steps) {
  LocalisationStateMachine m;
  ASSERT_EQ(m.Init(Params()), StateMachineError::kOk);
  std::uint64_t frame = 100;
  std::string got, want;
  for (const Step& s : steps) {
    frame += s.frame_gap;
    got += Letter(m.Update({frame, s.index, s.uniqueness, s.confidence}));
    want += s.expect;
  }
  EXPECT_EQ(got, want);
}

TEST(LocalisationState, ConfirmsASteadyTrack) {
  Expect({{10, 0.9f, 'S'}, {11, 0.9f, 'S'}, {12, 0.9f, 'K'}, {13, 0.9f, 'K'}});
}

TEST(LocalisationState, StartsLostAndIgnoresWeakMatches) {
  Expect({{-1, 0.0f, 'L'}, {10, 0.49f, 'L'}, {11, 0.9f, 'L', 0.95f}, {12, 0.5f, 'S'}});
}

TEST(LocalisationState, AJumpWhileSearchingRestartsTheCount) {
  // 10, 11 build a streak of 2; 50 is good but inconsistent: streak restarts at 1.
  Expect({{10, 0.9f, 'S'}, {11, 0.9f, 'S'}, {50, 0.9f, 'S'}, {51, 0.9f, 'S'}, {52, 0.9f, 'K'}});
}

TEST(LocalisationState, HysteresisKeepsLocalisedOnMediumConfidence) {
  // 0.4 is below enter (0.5) but above stay (0.3): it keeps LOCALISED but would not
  // have confirmed it.
  Expect({{10, 0.9f, 'S'},
          {11, 0.9f, 'S'},
          {12, 0.9f, 'K'},
          {13, 0.4f, 'K'},
          {14, 0.4f, 'K'},
          {15, 0.4f, 'K'}});
  Expect({{10, 0.4f, 'L'}, {11, 0.4f, 'L'}, {12, 0.4f, 'L'}});
}

TEST(LocalisationState, DropsToSearchingThenLost) {
  // Localised at frame 3; two misses (drop 2) -> SEARCHING; three more (lost 3) -> LOST.
  Expect({{10, 0.9f, 'S'},
          {11, 0.9f, 'S'},
          {12, 0.9f, 'K'},
          {13, 0.1f, 'K'},
          {-1, 0.0f, 'S'},
          {-1, 0.0f, 'S'},
          {-1, 0.0f, 'S'},
          {-1, 0.0f, 'L'}});
}

TEST(LocalisationState, OneMissDoesNotDrop) {
  Expect({{10, 0.9f, 'S'},
          {11, 0.9f, 'S'},
          {12, 0.9f, 'K'},
          {-1, 0.0f, 'K'},
          // The anchor is 12 two frames ago: 14 is within 0.8*2-1 .. 1.2*2+1 = 0.6..3.4.
          {14, 0.9f, 'K'},
          {15, 0.9f, 'K'}});
}

TEST(LocalisationState, KidnappedRobotRelocalisesElsewhere) {
  // Localised near 12, then confident matches at 80.. : they are inconsistent, so after
  // two (drop) the machine searches, and the new track confirms after three more.
  Expect({{10, 0.9f, 'S'},
          {11, 0.9f, 'S'},
          {12, 0.9f, 'K'},
          {80, 0.9f, 'K'},
          {81, 0.9f, 'S'},
          {82, 0.9f, 'S'},
          {83, 0.9f, 'S'},
          {84, 0.9f, 'K'}});
}

TEST(LocalisationState, DroppedFramesWidenTheVelocityBand) {
  // Three frames pass between 11 and 14 (gap 3): 14 - 11 = 3 is within 1.4..4.6.
  Expect({{10, 0.9f, 'S'}, {11, 0.9f, 'S'}, {14, 0.9f, 'K', 0.5f, 3}});
  // A jump of 8 over the same gap is not.
  Expect({{10, 0.9f, 'S'}, {11, 0.9f, 'S'}, {19, 0.9f, 'S', 0.5f, 3}});
}

TEST(LocalisationState, StandingStillOrReversingIsInconsistent) {
  // vmin 0.8 - slack 1 = -0.2: standing still (0) is allowed, going back 2 is not.
  Expect({{10, 0.9f, 'S'}, {10, 0.9f, 'S'}, {10, 0.9f, 'K'}});
  Expect({{10, 0.9f, 'S'}, {8, 0.9f, 'S'}, {6, 0.9f, 'S'}});
}

TEST(LocalisationState, AmbiguousMatchesNeverLocalise) {
  Expect({{10, 0.9f, 'L', 0.95f}, {11, 0.9f, 'L', 0.95f}, {12, 0.9f, 'L', 0.95f}});
}

TEST(LocalisationState, RejectsBadParameters) {
  LocalisationStateMachine m;
  StateMachineParams p = Params();
  p.stay_confidence = 0.6f;
  EXPECT_EQ(m.Init(p), StateMachineError::kBadConfidence);
  p = Params();
  p.max_uniqueness = 1.5f;
  EXPECT_EQ(m.Init(p), StateMachineError::kBadUniqueness);
  p = Params();
  p.drop_frames = 0;
  EXPECT_EQ(m.Init(p), StateMachineError::kBadCounts);
  p = Params();
  p.vmin = 2.0;
  EXPECT_EQ(m.Init(p), StateMachineError::kBadVelocity);
}

// Each refusal reaches the user as a sentence naming the keys to fix.
TEST(LocalisationState, EachErrorNamesTheKeysToFix) {
  const std::pair<StateMachineError, const char*> cases[] = {
      {StateMachineError::kBadConfidence, "stay_confidence"},
      {StateMachineError::kBadUniqueness, "max_uniqueness"},
      {StateMachineError::kBadCounts, "confirm_frames"},
      {StateMachineError::kBadVelocity, "vmin"},
  };
  for (const auto& [error, key] : cases)
    EXPECT_NE(std::string(StateMachineErrorMessage(error)).find(key), std::string::npos) << key;
}

}  // namespace
}  // namespace skyloc::dsp
