// Real-time setup: what is refused comes back as a warning naming the limit and the fix.
// The refusals are provoked in a forked child that drops to an unprivileged user (when
// run as root) and lowers its own limits, so the test does not depend on who runs it.
#include "skyloc/platform/realtime.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <string>

#include "support/emulator.h"

namespace skyloc {
namespace {

// Runs `options` in a child without privileges and returns the warnings it produced,
// joined by newlines ("OK" for an accepted setting).
std::string RefusedInChild(const RealtimeOptions& options) {
  if (skyloc::testing::UnderUserModeEmulator())
    return "SKIP";
  int fds[2];
  if (::pipe(fds) != 0)
    return "pipe failed";
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(fds[0]);
    const struct rlimit zero { 0, 0 };
    ::setrlimit(RLIMIT_RTPRIO, &zero);
    ::setrlimit(RLIMIT_MEMLOCK, &zero);
    if (::geteuid() == 0 && ::setresuid(65534, 65534, 65534) != 0)
      ::_exit(2);
    const RealtimeReport r = ApplyRealtime(options);
    std::string text;
    for (const Status* s : {&r.scheduling, &r.memory_lock, &r.affinity}) {
      text += s->ok() ? "OK" : s->message();
      text += '\n';
    }
    const ssize_t n = ::write(fds[1], text.data(), text.size());
    ::_exit(n == static_cast<ssize_t>(text.size()) ? 0 : 3);
  }
  ::close(fds[1]);
  std::string text;
  char buffer[1024];
  ssize_t n;
  while ((n = ::read(fds[0], buffer, sizeof buffer)) > 0)
    text.append(buffer, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  return text;
}

TEST(Realtime, NothingRequestedIsAllOk) {
  EXPECT_TRUE(ApplyRealtime({}).all_ok());
}

TEST(Realtime, RefusedSchedulingNamesTheLimit) {
  RealtimeOptions o;
  o.sched_fifo_priority = 50;
  const std::string text = RefusedInChild(o);
  if (text == "SKIP")
    GTEST_SKIP() << "qemu-user spins in a forked child that calls setresuid (support/emulator.h)";
  EXPECT_NE(text.find("SCHED_FIFO priority 50 refused"), std::string::npos) << text;
  EXPECT_NE(text.find("RLIMIT_RTPRIO is 0"), std::string::npos) << text;
  EXPECT_NE(text.find("LimitRTPRIO=50"), std::string::npos) << text;
}

TEST(Realtime, RefusedMemoryLockNamesTheLimit) {
#if defined(SKYLOC_SANITIZED)
  // AddressSanitizer intercepts mlockall() and ignores it (returns 0), so it cannot fail.
  GTEST_SKIP() << "mlockall is a no-op under AddressSanitizer";
#endif
  RealtimeOptions o;
  o.lock_memory = true;
  const std::string text = RefusedInChild(o);
  if (text == "SKIP")
    GTEST_SKIP() << "qemu-user spins in a forked child that calls setresuid (support/emulator.h)";
  EXPECT_NE(text.find("mlockall refused (RLIMIT_MEMLOCK is 0 bytes"), std::string::npos) << text;
  EXPECT_NE(text.find("LimitMEMLOCK=infinity"), std::string::npos) << text;
}

TEST(Realtime, MissingCpuIsAWarning) {
  RealtimeOptions o;
  o.cpu = 1000;
  const RealtimeReport r = ApplyRealtime(o);
  ASSERT_FALSE(r.affinity.ok());
  EXPECT_NE(std::string(r.affinity.message()).find("cannot pin to CPU 1000"), std::string::npos)
      << r.affinity.message();
  EXPECT_TRUE(r.scheduling.ok());
}

}  // namespace
}  // namespace skyloc
