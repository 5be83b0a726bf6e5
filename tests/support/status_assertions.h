// gtest assertions on Status: a failure prints the code and the message, which names the
// device or file and the fix, instead of "false".
//
//   ASSERT_OK(camera.Open());
#pragma once

#include <gtest/gtest.h>

#include "skyloc/platform/status.h"

namespace skyloc::testing {

inline ::testing::AssertionResult IsOk(const Status& status) {
  if (status.ok())
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << StatusCodeName(status.code()) << ": " << status.message();
}

}  // namespace skyloc::testing

#define ASSERT_OK(expr) ASSERT_TRUE(::skyloc::testing::IsOk(expr))
