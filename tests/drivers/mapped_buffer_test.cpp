#include "skyloc/drivers/mapped_buffer.h"

#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <utility>

#include "skyloc/platform/unique_fd.h"

namespace skyloc::drivers {
namespace {

TEST(MappedBuffer, MapsTheFileAndMovesOwnership) {
  UniqueFd fd(::memfd_create("mapped-buffer-test", MFD_CLOEXEC));
  ASSERT_TRUE(fd.is_valid());
  const char text[] = "skyloc";
  ASSERT_EQ(::pwrite(fd.get(), text, sizeof(text), 4096), static_cast<ssize_t>(sizeof(text)));

  MappedBuffer a;
  EXPECT_FALSE(a.is_mapped());
  ASSERT_TRUE(a.Map(fd.get(), 4096, sizeof(text)).ok());
  ASSERT_TRUE(a.is_mapped());
  EXPECT_STREQ(reinterpret_cast<const char*>(a.data()), "skyloc");

  // Writes through the file show through the shared mapping (how a device fills it).
  ASSERT_EQ(::pwrite(fd.get(), "S", 1, 4096), 1);
  EXPECT_EQ(a.data()[0], 'S');

  MappedBuffer b(std::move(a));
  EXPECT_FALSE(a.is_mapped());  // NOLINT(bugprone-use-after-move): moved-from is empty
  EXPECT_EQ(b.size(), sizeof(text));
  b.Unmap();
  EXPECT_FALSE(b.is_mapped());
}

TEST(MappedBuffer, FailureSavesErrno) {
  MappedBuffer m;
  const Status s = m.Map(-1, 0, 4096);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.sys_errno(), EBADF);
  EXPECT_FALSE(m.is_mapped());
}

}  // namespace
}  // namespace skyloc::drivers
