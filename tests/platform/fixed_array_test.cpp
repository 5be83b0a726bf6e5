#include "skyloc/platform/fixed_array.h"

#include <gtest/gtest.h>

#include <limits>

namespace skyloc {
namespace {

TEST(FixedArray, AllocatesValueInitialised) {
  FixedArray<float> a;
  ASSERT_TRUE(a.Allocate(100).ok());
  EXPECT_EQ(a.size(), 100u);
  for (float v : a)
    EXPECT_EQ(v, 0.0f);
  a[99] = 3.0f;
  EXPECT_EQ(a.span().back(), 3.0f);
}

TEST(FixedArray, ImpossibleSizeIsAnErrorNotACrash) {
#if defined(SKYLOC_SANITIZED)
  GTEST_SKIP() << "AddressSanitizer aborts on impossible allocations by design";
#else
  FixedArray<double> a;
  // Almost the whole address space in bytes: impossible on 32-bit (where max / 16 doubles,
  // 2 GB, can succeed) and on 64-bit alike.
  Status s = a.Allocate(std::numeric_limits<std::size_t>::max() / sizeof(double) - 1);
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(a.size(), 0u);
#endif
}

}  // namespace
}  // namespace skyloc
