// The one mapping from dsp's errors to a Status: the code by the kind of failure, and the
// message as "context: the error's own sentence".
#include "skyloc/drivers/dsp_status.h"

#include <gtest/gtest.h>

#include <string>

namespace skyloc::drivers {
namespace {

TEST(DspStatus, PrefixesTheErrorsOwnSentenceWithItsContext) {
  const Status s = DspStatus(dsp::LensError::kBadRadius, "lens of %s", "camera.toml");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(s.message()), std::string("lens of camera.toml: ") +
                                          dsp::LensErrorMessage(dsp::LensError::kBadRadius));
}

TEST(DspStatus, CodesSayWhatKindOfFailureItIs) {
  // A call in the wrong state, a full fixed buffer, input with nothing to measure, a bad
  // parameter: four codes a caller decides on.
  EXPECT_EQ(StatusCodeOf(dsp::AttitudeError::kNotInitialised), StatusCode::kFailedPrecondition);
  EXPECT_EQ(StatusCodeOf(dsp::AttitudeError::kGap), StatusCode::kDataLoss);
  EXPECT_EQ(StatusCodeOf(dsp::SeqSlamError::kDatabaseFull), StatusCode::kResourceExhausted);
  EXPECT_EQ(StatusCodeOf(dsp::SeqSlamError::kEmptyDatabase), StatusCode::kFailedPrecondition);
  EXPECT_EQ(StatusCodeOf(dsp::StripAlignmentError::kFlat), StatusCode::kDataLoss);
  EXPECT_EQ(StatusCodeOf(dsp::LensError::kBadFieldOfView), StatusCode::kInvalidArgument);
}

TEST(DspStatus, NoErrorIsOk) {
  EXPECT_EQ(StatusCodeOf(dsp::AttitudeError::kOk), StatusCode::kOk);
  EXPECT_EQ(StatusCodeOf(dsp::LensError::kOk), StatusCode::kOk);
  EXPECT_EQ(StatusCodeOf(dsp::SeqSlamError::kOk), StatusCode::kOk);
  EXPECT_EQ(StatusCodeOf(dsp::Surf1dError::kOk), StatusCode::kOk);
  EXPECT_EQ(StatusCodeOf(dsp::DescriptorError{}), StatusCode::kOk);
}

}  // namespace
}  // namespace skyloc::drivers
