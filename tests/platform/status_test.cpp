#include "skyloc/platform/status.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace skyloc {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

TEST(Status, DefaultIsOk) {
  Status s;
  EXPECT_TRUE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kOk);
  EXPECT_STREQ(s.message(), "");
}

TEST(Status, ErrorFormatsMessage) {
  Status s =
      Status::Error(StatusCode::kInvalidArgument, "key '%s' = %d is out of range", "bands", 7);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_STREQ(s.message(), "key 'bands' = 7 is out of range");
}

TEST(Status, ErrorWithOkCodeBecomesInternal) {
  EXPECT_EQ(Status::Error(StatusCode::kOk, "x").code(), StatusCode::kInternal);
}

TEST(Status, LongMessageIsTruncatedWithEllipsis) {
  std::string longname(1000, 'a');
  Status s = Status::Error(StatusCode::kNotFound, "%s", longname.c_str());
  EXPECT_EQ(std::strlen(s.message()), Status::kMessageCapacity - 1);
  EXPECT_THAT(std::string(s.message()), ::testing::EndsWith("..."));
}

TEST(Status, FromErrnoKeepsErrnoAndMapsCode) {
  Status s = Status::FromErrno(ENOENT, "open %s", "/dev/video9");
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_EQ(s.sys_errno(), ENOENT);
  EXPECT_STREQ(s.message(), "open /dev/video9: No such file or directory");
  EXPECT_EQ(Status::FromErrno(ENODEV, "x").code(), StatusCode::kUnavailable);
  EXPECT_EQ(Status::FromErrno(EACCES, "x").code(), StatusCode::kPermissionDenied);
  EXPECT_EQ(Status::FromErrno(ETIMEDOUT, "x").code(), StatusCode::kDeadlineExceeded);
}

TEST(Status, AddContextPrefixes) {
  Status s = Status::Error(StatusCode::kDataLoss, "chunk 3 at offset 4096: CRC mismatch");
  s.AddContext("loading %s", "route.db");
  EXPECT_STREQ(s.message(), "loading route.db: chunk 3 at offset 4096: CRC mismatch");
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
}

Result<int> ParsePositive(int v) {
  if (v <= 0)
    return Status::Error(StatusCode::kOutOfRange, "%d is not positive", v);
  return v;
}

Result<int> Doubled(int v) {
  SKYLOC_TRY_ASSIGN(int parsed, ParsePositive(v));
  return parsed * 2;
}

Status CheckBoth(int a, int b) {
  SKYLOC_TRY(ParsePositive(a));
  SKYLOC_TRY(ParsePositive(b));
  return Status::Ok();
}

TEST(Result, ValueAndError) {
  Result<int> ok = Doubled(21);
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(*ok, 42);
  Result<int> bad = Doubled(-1);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kOutOfRange);
  EXPECT_STREQ(bad.status().message(), "-1 is not positive");
}

TEST(Result, TryReturnsFirstFailure) {
  EXPECT_TRUE(CheckBoth(1, 2).ok());
  EXPECT_THAT(CheckBoth(1, -5).message(), StartsWith("-5"));
  EXPECT_THAT(CheckBoth(-3, -5).message(), HasSubstr("-3"));
}

TEST(Result, BuiltFromOkStatusIsAnInternalError) {
  Result<int> r{Status::Ok()};
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInternal);
}

}  // namespace
}  // namespace skyloc
