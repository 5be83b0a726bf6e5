// Signals set the flags the loop reads, and nothing else happens (the process survives).
#include "skyloc/platform/signals.h"

#include <gtest/gtest.h>
#include <signal.h>

namespace skyloc {
namespace {

// SIGHUP too: a teach over SSH whose connection drops must commit, not die uncommitted.
TEST(Signals, TermIntAndHupRequestStop) {
  ASSERT_TRUE(InstallSignalHandlers().ok());
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
    ClearSignalFlags();
    EXPECT_FALSE(StopRequested());
    ASSERT_EQ(::raise(sig), 0);
    EXPECT_TRUE(StopRequested()) << sig;
  }
  ClearSignalFlags();
}

TEST(Signals, Usr1RequestsOneReport) {
  ASSERT_TRUE(InstallSignalHandlers().ok());
  ClearSignalFlags();
  EXPECT_FALSE(TakeReportRequest());
  ASSERT_EQ(::raise(SIGUSR1), 0);
  ASSERT_EQ(::raise(SIGUSR1), 0);
  EXPECT_TRUE(TakeReportRequest());
  EXPECT_FALSE(TakeReportRequest());
  EXPECT_FALSE(StopRequested());
}

TEST(Signals, SigpipeIsIgnored) {
  ASSERT_TRUE(InstallSignalHandlers().ok());
  ASSERT_EQ(::raise(SIGPIPE), 0);  // would kill the test process if not ignored
  SUCCEED();
}

// A file grown past RLIMIT_FSIZE must be a write error (EFBIG) the route database reports
// and commits around, not a SIGXFSZ that kills teach with its frames uncommitted.
TEST(Signals, SigxfszIsIgnored) {
  ASSERT_TRUE(InstallSignalHandlers().ok());
  ASSERT_EQ(::raise(SIGXFSZ), 0);  // would kill the test process if not ignored
  SUCCEED();
}

}  // namespace
}  // namespace skyloc
