// The teach button's debouncing on edge sequences: bounce within the window is ignored, a
// clean press is accepted once, a long hold (even with a glitch) is one press.
#include "firmware/button.h"

#include <gtest/gtest.h>

namespace skyloc::firmware {
namespace {

using std::chrono::milliseconds;

drivers::ButtonEvent Edge(bool pressed, int ms) {
  return {pressed, milliseconds(ms)};
}

// Polls every millisecond over [from, to) and counts accepted presses.
int PressesBetween(ButtonDebouncer& b, int from, int to) {
  int presses = 0;
  for (int t = from; t < to; ++t)
    presses += b.TakePress(milliseconds(t)) ? 1 : 0;
  return presses;
}

TEST(ButtonDebouncer, ACleanPressIsAcceptedOnceAfterTheWindow) {
  ButtonDebouncer b(milliseconds(50));
  EXPECT_EQ(PressesBetween(b, 0, 100), 0);
  b.OnEdge(Edge(true, 100));
  EXPECT_EQ(PressesBetween(b, 100, 150), 0);  // not yet 50 ms
  EXPECT_TRUE(b.TakePress(milliseconds(150)));
  EXPECT_EQ(PressesBetween(b, 151, 300), 0);
  b.OnEdge(Edge(false, 300));
  EXPECT_EQ(PressesBetween(b, 300, 600), 0);
}

TEST(ButtonDebouncer, BounceWithinTheWindowIsIgnored) {
  ButtonDebouncer b(milliseconds(50));
  // A press that bounces for 9 ms: the window starts at its last edge.
  b.OnEdge(Edge(true, 100));
  b.OnEdge(Edge(false, 103));
  b.OnEdge(Edge(true, 105));
  b.OnEdge(Edge(false, 107));
  b.OnEdge(Edge(true, 109));
  EXPECT_EQ(PressesBetween(b, 100, 159), 0);
  EXPECT_EQ(PressesBetween(b, 159, 400), 1);
  // Short spikes (a glitch on an idle line) never make a press.
  ButtonDebouncer idle(milliseconds(50));
  for (int t = 0; t < 1000; t += 40) {
    idle.OnEdge(Edge(true, t));
    idle.OnEdge(Edge(false, t + 20));
  }
  EXPECT_EQ(PressesBetween(idle, 0, 1100), 0);
}

TEST(ButtonDebouncer, ALongHoldIsOnePressEvenWithAGlitch) {
  ButtonDebouncer b(milliseconds(50));
  b.OnEdge(Edge(true, 0));
  EXPECT_EQ(PressesBetween(b, 0, 2000), 1);
  // A 5 ms dropout while held: not a release, so not a second press.
  b.OnEdge(Edge(false, 2000));
  b.OnEdge(Edge(true, 2005));
  EXPECT_EQ(PressesBetween(b, 2000, 5000), 0);
  // A real release, then a second press.
  b.OnEdge(Edge(false, 5000));
  EXPECT_EQ(PressesBetween(b, 5000, 5100), 0);
  b.OnEdge(Edge(true, 5100));
  EXPECT_EQ(PressesBetween(b, 5100, 5200), 1);
}

TEST(ButtonDebouncer, AReleaseSeenOnlyThroughEdgesArmsTheNextPress) {
  // The caller does not poll during the release: the edges alone show it was steady.
  ButtonDebouncer b(milliseconds(50));
  b.OnEdge(Edge(true, 0));
  EXPECT_TRUE(b.TakePress(milliseconds(60)));
  b.OnEdge(Edge(false, 100));
  b.OnEdge(Edge(true, 200));
  EXPECT_FALSE(b.TakePress(milliseconds(240)));
  EXPECT_TRUE(b.TakePress(milliseconds(250)));
}

TEST(ButtonDebouncer, ZeroDebounceAcceptsAtTheEdge) {
  ButtonDebouncer b(milliseconds(0));
  b.OnEdge(Edge(true, 10));
  EXPECT_TRUE(b.TakePress(milliseconds(10)));
  EXPECT_FALSE(b.TakePress(milliseconds(11)));
}

}  // namespace
}  // namespace skyloc::firmware
