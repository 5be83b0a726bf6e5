#include "firmware/dsp_status.h"

namespace skyloc::firmware {

StatusCode StatusCodeOf(dsp::AttitudeError e) {
  switch (e) {
    case dsp::AttitudeError::kOk:
      return StatusCode::kOk;
    case dsp::AttitudeError::kNotInitialised:
      return StatusCode::kFailedPrecondition;
    case dsp::AttitudeError::kNonFinite:
    case dsp::AttitudeError::kTimestampNotIncreasing:
    case dsp::AttitudeError::kGap:
    case dsp::AttitudeError::kNoGravity:
      return StatusCode::kDataLoss;  // a sample that carries no attitude
    default:
      return StatusCode::kInvalidArgument;  // the filter's parameters
  }
}

StatusCode StatusCodeOf(dsp::HeadingError e) {
  return e == dsp::HeadingError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::HorizonStripError e) {
  return e == dsp::HorizonStripError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::LensError e) {
  return e == dsp::LensError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::StateMachineError e) {
  return e == dsp::StateMachineError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::SampleLutError e) {
  return e == dsp::SampleLutError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::SegmentationError e) {
  return e == dsp::SegmentationError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(dsp::SeqSlamError e) {
  switch (e) {
    case dsp::SeqSlamError::kOk:
      return StatusCode::kOk;
    case dsp::SeqSlamError::kDatabaseFull:
      return StatusCode::kResourceExhausted;
    case dsp::SeqSlamError::kNotInitialised:
    case dsp::SeqSlamError::kEmptyDatabase:
    case dsp::SeqSlamError::kRouteNotFinished:
    case dsp::SeqSlamError::kRouteFinished:
      return StatusCode::kFailedPrecondition;
    default:
      return StatusCode::kInvalidArgument;  // parameters and sizes
  }
}

StatusCode StatusCodeOf(dsp::ShError e) {
  switch (e) {
    case dsp::ShError::kOk:
      return StatusCode::kOk;
    case dsp::ShError::kNotInitialised:
      return StatusCode::kFailedPrecondition;
    case dsp::ShError::kTableTooLarge:
      return StatusCode::kResourceExhausted;
    default:
      return StatusCode::kInvalidArgument;
  }
}

StatusCode StatusCodeOf(dsp::StripAlignmentError e) {
  switch (e) {
    case dsp::StripAlignmentError::kOk:
      return StatusCode::kOk;
    case dsp::StripAlignmentError::kFlat:
      return StatusCode::kDataLoss;  // nothing to align: the strip carries no turn
    default:
      return StatusCode::kInvalidArgument;
  }
}

StatusCode StatusCodeOf(dsp::Surf1dError e) {
  switch (e) {
    case dsp::Surf1dError::kOk:
      return StatusCode::kOk;
    case dsp::Surf1dError::kNotInitialised:
      return StatusCode::kFailedPrecondition;
    case dsp::Surf1dError::kTooManyFeatures:
      return StatusCode::kResourceExhausted;
    default:
      return StatusCode::kInvalidArgument;
  }
}

StatusCode StatusCodeOf(dsp::VanillaError e) {
  return e == dsp::VanillaError::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

StatusCode StatusCodeOf(const dsp::DescriptorError& e) {
  return e.ok() ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

const char* DspErrorMessage(dsp::AttitudeError e) {
  return dsp::AttitudeErrorMessage(e);
}
const char* DspErrorMessage(dsp::HeadingError e) {
  return dsp::HeadingErrorMessage(e);
}
const char* DspErrorMessage(dsp::HorizonStripError e) {
  return dsp::HorizonStripErrorMessage(e);
}
const char* DspErrorMessage(dsp::LensError e) {
  return dsp::LensErrorMessage(e);
}
const char* DspErrorMessage(dsp::StateMachineError e) {
  return dsp::StateMachineErrorMessage(e);
}
const char* DspErrorMessage(dsp::SampleLutError e) {
  return dsp::SampleLutErrorMessage(e);
}
const char* DspErrorMessage(dsp::SegmentationError e) {
  return dsp::SegmentationErrorMessage(e);
}
const char* DspErrorMessage(dsp::SeqSlamError e) {
  return dsp::SeqSlamErrorMessage(e);
}
const char* DspErrorMessage(dsp::ShError e) {
  return dsp::ShErrorMessage(e);
}
const char* DspErrorMessage(dsp::StripAlignmentError e) {
  return dsp::StripAlignmentErrorMessage(e);
}
const char* DspErrorMessage(dsp::Surf1dError e) {
  return dsp::Surf1dErrorMessage(e);
}
const char* DspErrorMessage(dsp::VanillaError e) {
  return dsp::VanillaErrorMessage(e);
}
const char* DspErrorMessage(const dsp::DescriptorError& e) {
  return e.message;
}

}  // namespace skyloc::firmware
