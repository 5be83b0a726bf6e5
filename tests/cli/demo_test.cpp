// `skyloc demo --quick` runs on a configuration built in memory: it creates nothing in
// /tmp while it runs (watched with inotify, so a file made and removed again is seen too),
// and the folder it keeps its route in, in the working directory, is gone at the end.
#include <gtest/gtest.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
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

TEST(Demo, QuickRunLeavesNothingInTmpOrTheWorkingDirectory) {
  const skyloc::testing::ScratchDir work("skyloc_cli_demo_");
  ASSERT_FALSE(work.path().empty());
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(work.path());

  CreationWatch tmp("/tmp");
  ASSERT_TRUE(tmp.ok()) << std::strerror(errno);
  char quick[] = "--quick";
  char* args[] = {quick};
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int rc = RunDemo(args);
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  std::vector<std::string> created = tmp.Created();
  std::filesystem::current_path(before);

  ASSERT_EQ(rc, kExitOk) << out << err;
  EXPECT_NE(out.find("3. result:"), std::string::npos) << out;
  // Other processes may use /tmp meanwhile; the demo's names start with "skyloc_demo".
  for (const std::string& name : created)
    EXPECT_NE(name.rfind("skyloc_demo", 0), 0u) << "the demo created /tmp/" << name;
  EXPECT_EQ(out.find("/tmp"), std::string::npos) << out;
  EXPECT_EQ(err.find("/tmp"), std::string::npos) << err;
  EXPECT_TRUE(std::filesystem::is_empty(work.path())) << work.path();
}

}  // namespace
}  // namespace skyloc::cli
