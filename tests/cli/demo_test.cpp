// `skyloc demo --quick` runs on a configuration built in memory: the only thing it creates
// is the folder of its route database under $TMPDIR (watched with inotify, so a file made
// and removed again is seen too), gone at the end. The same run is the demo's accuracy
// floor on every target (x86-64, aarch64 and armhf: one run, not two, since a quick demo
// under qemu-arm takes most of a minute).
#include <gtest/gtest.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "support/scratch_dir.h"

namespace skyloc::cli {
namespace {

// The names of the entries created in `dir` since the watch began.
class CreationWatch {
 public:
  explicit CreationWatch(const char* dir) {
    fd_ = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
    if (fd_ >= 0)
      watch_ = ::inotify_add_watch(fd_, dir, IN_CREATE | IN_MOVED_TO);
  }
  ~CreationWatch() {
    if (fd_ >= 0)
      ::close(fd_);
  }
  CreationWatch(const CreationWatch&) = delete;
  CreationWatch& operator=(const CreationWatch&) = delete;

  bool ok() const { return fd_ >= 0 && watch_ >= 0; }

  std::vector<std::string> Created() {
    std::vector<std::string> names;
    alignas(inotify_event) char buffer[64 * (sizeof(inotify_event) + NAME_MAX + 1)];
    for (;;) {
      const ssize_t n = ::read(fd_, buffer, sizeof buffer);
      if (n <= 0)
        break;
      for (ssize_t at = 0; at < n;) {
        const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
        if (event->len > 0)
          names.emplace_back(event->name);
        at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
      }
    }
    return names;
  }

 private:
  int fd_ = -1;
  int watch_ = -1;
};

// The demo writes no configuration file: its route database is the only file it makes, in
// a folder of its own under $TMPDIR, and nothing is left there or in the working directory.
TEST(Demo, QuickRunWritesOnlyItsRouteAndLeavesNothing) {
  const skyloc::testing::ScratchDir work("skyloc_cli_demo_");
  const skyloc::testing::ScratchDir tmp("skyloc_cli_demo_tmp_");
  ASSERT_FALSE(work.path().empty());
  ASSERT_FALSE(tmp.path().empty());
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(work.path());
  const char* old_tmpdir = std::getenv("TMPDIR");
  const std::string saved_tmpdir = old_tmpdir != nullptr ? old_tmpdir : "";
  ::setenv("TMPDIR", tmp.path().c_str(), 1);

  CreationWatch watch(tmp.path().c_str());
  ASSERT_TRUE(watch.ok()) << std::strerror(errno);
  char quick[] = "--quick";
  char* args[] = {quick};
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int rc = RunDemo(args);
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  const std::vector<std::string> created = watch.Created();
  std::filesystem::current_path(before);
  if (old_tmpdir != nullptr)
    ::setenv("TMPDIR", saved_tmpdir.c_str(), 1);
  else
    ::unsetenv("TMPDIR");

  ASSERT_EQ(rc, kExitOk) << out << err;
  EXPECT_NE(out.find("3. result:"), std::string::npos) << out;
  // The quick demo (a camera at 10 fps, a standing start and a stop in both runs, the
  // repeat 1.5x faster) localises 115 of its 160 repeat frames, all correctly within 2 m,
  // on x86-64, aarch64 and armhf alike (the worlds, frames and descriptors agree bit for
  // bit, tests/sim/same_bits_test.cpp). The floor, at least 90 correct LOCALISED frames,
  // fails a build that loses a fifth of them, on any target.
  const std::size_t summary = out.find("LOCALISED ", out.find("3. result:"));
  ASSERT_NE(summary, std::string::npos) << out;
  unsigned long long localised = 0, frames = 0, correct = 0;
  ASSERT_EQ(
      std::sscanf(out.c_str() + summary, "LOCALISED %llu of %llu frames, %llu of them correct",
                  &localised, &frames, &correct),
      3)
      << out;
  EXPECT_EQ(frames, 160u) << out;
  EXPECT_GE(correct, 90u) << out;
  EXPECT_LE(correct, localised) << out;
  ASSERT_EQ(created.size(), 1u) << "the demo made more than its route's folder";
  EXPECT_EQ(created[0].rfind("skyloc_demo_", 0), 0u) << created[0];
  EXPECT_EQ(err.find(".toml"), std::string::npos) << err;  // no configuration file
  EXPECT_NE(err.find(tmp.path() + "/" + created[0] + "/route.db"), std::string::npos) << err;
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path())) << tmp.path();
  EXPECT_TRUE(std::filesystem::is_empty(work.path())) << work.path();
}

}  // namespace
}  // namespace skyloc::cli
