// SKYLOC_TRY around AddContext() on a temporary: the returned Status must carry the whole
// message (it used to bind a reference to the destroyed temporary; ASan builds catch it).
#include <gtest/gtest.h>

#include <string>

#include "skyloc/platform/status.h"

namespace skyloc {
namespace {

Status Fails() {
  return Status::Error(StatusCode::kDataLoss, "inner problem");
}

Status WithContext() {
  SKYLOC_TRY(Fails().AddContext("outer step"));
  return Status::Ok();
}

Result<int> ResultWithContext() {
  SKYLOC_TRY(Fails().AddContext("in a Result"));
  return 1;
}

TEST(StatusTry, ContextOnATemporaryIsKept) {
  const Status s = WithContext();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_EQ(std::string(s.message()), "outer step: inner problem");
  const Result<int> r = ResultWithContext();
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(std::string(r.status().message()), "in a Result: inner problem");
}

}  // namespace
}  // namespace skyloc
