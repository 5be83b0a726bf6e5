// Files the program creates for itself (a route's lock and temporary file) are created
// without following a link planted at their path, and anything but a regular file there is
// refused naming the file and the fix; files a user names are opened for reading the same
// way.
#include "skyloc/platform/regular_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <string>

#include "support/scratch_dir.h"

namespace skyloc {
namespace {

std::string Message(const Status& s) {
  return s.message();
}

TEST(CreateRegularFile, CreatesARegularFileWithTheMode) {
  testing::ScratchDir dir("regular_file_");
  const std::string path = dir.path() + "/a.lock";
  UniqueFd fd;
  ASSERT_TRUE(CreateRegularFile(path.c_str(), O_RDWR, 0600, "the lock", "fix", &fd).ok());
  ASSERT_TRUE(fd.is_valid());
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(st.st_mode & 0177, 0u);
  EXPECT_EQ(::fcntl(fd.get(), F_GETFL) & O_NONBLOCK, 0);
  EXPECT_EQ(::write(fd.get(), "x", 1), 1);
}

TEST(CreateRegularFile, RefusesAFifoNamingTheFileAndTheFix) {
  testing::ScratchDir dir("regular_file_");
  const std::string path = dir.path() + "/a.tmp";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  UniqueFd fd;
  // O_RDWR opens a FIFO (write-only fails at the open, ENXIO, with no reader): the check
  // after the open is what refuses it.
  const Status s =
      CreateRegularFile(path.c_str(), O_RDWR, 0644, "the teach's temporary file", "remove it", &fd);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Message(s),
            "the teach's temporary file " + path + " is a FIFO, not a regular file: remove it");
  EXPECT_FALSE(fd.is_valid());
}

TEST(CreateRegularFile, DoesNotFollowALink) {
  testing::ScratchDir dir("regular_file_");
  const std::string target = dir.path() + "/target";
  {
    std::ofstream out(target);
    out << "not ours";
  }
  const std::string path = dir.path() + "/a.lock";
  ASSERT_EQ(::symlink(target.c_str(), path.c_str()), 0);
  UniqueFd fd;
  const Status s =
      CreateRegularFile(path.c_str(), O_WRONLY | O_TRUNC, 0644, "the lock", "fix", &fd);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(Message(s).find("cannot create the lock " + path), std::string::npos) << Message(s);
  std::ifstream in(target);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "not ours");
}

TEST(OpenRegularFile, RefusesAFifoAskingForARegularFile) {
  testing::ScratchDir dir("regular_file_");
  const std::string path = dir.path() + "/a.png";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  UniqueFd fd;
  const Status s = OpenRegularFile(path.c_str(), O_RDONLY, "image", &fd);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Message(s), "image " + path + " is a FIFO, not a regular file: name a regular file");
}

}  // namespace
}  // namespace skyloc
