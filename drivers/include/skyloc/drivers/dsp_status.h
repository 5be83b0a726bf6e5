// The one mapping from dsp's error values to a Status: every caller of dsp (the drivers,
// the pipeline, the frame loop, the tools) turns a dsp error into the same code and the
// same sentence, prefixed with what it was doing:
//   if (e != dsp::SeqSlamError::kOk) return DspStatus(e, "[seqslam]");
// dsp itself stays free of platform/ (tests/lint): its errors are plain enums with a
// message function each, and this header, in the lowest layer that sees both, is where
// they meet Status.
#pragma once

#include <cstdarg>
#include <cstdio>

#include "skyloc/dsp/attitude_filter.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/sample_lut.h"
#include "skyloc/dsp/segmentation.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/sh_grid.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/dsp/strip_alignment.h"
#include "skyloc/dsp/surf1d.h"
#include "skyloc/dsp/vanilla_descriptor.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// The code of each dsp error: a wrong parameter or size is kInvalidArgument, a call in the
// wrong state kFailedPrecondition, a full fixed buffer kResourceExhausted, input that
// carries nothing to measure kDataLoss. Header-only, so a program (a fuzz target) links
// the messages of only the dsp parts it uses.

// An error whose every failure is a wrong parameter or size.
template <typename E>
StatusCode ParameterErrorCode(E e) {
  return e == E::kOk ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

inline StatusCode StatusCodeOf(dsp::AttitudeError e) {
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

inline StatusCode StatusCodeOf(dsp::HeadingError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::HorizonStripError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::LensError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::StateMachineError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::SampleLutError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::SegmentationError e) {
  return ParameterErrorCode(e);
}

inline StatusCode StatusCodeOf(dsp::SeqSlamError e) {
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

inline StatusCode StatusCodeOf(dsp::ShError e) {
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

inline StatusCode StatusCodeOf(dsp::StripAlignmentError e) {
  switch (e) {
    case dsp::StripAlignmentError::kOk:
      return StatusCode::kOk;
    case dsp::StripAlignmentError::kFlat:
      return StatusCode::kDataLoss;  // nothing to align: the strip carries no turn
    default:
      return StatusCode::kInvalidArgument;
  }
}

inline StatusCode StatusCodeOf(dsp::Surf1dError e) {
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

inline StatusCode StatusCodeOf(dsp::VanillaError e) {
  return ParameterErrorCode(e);
}

// A descriptor that failed at start-up (Init: its options) or on a frame (Compute: the
// frame is not what the descriptor was built for): kInvalidArgument.
inline StatusCode StatusCodeOf(const dsp::DescriptorError& e) {
  return e.ok() ? StatusCode::kOk : StatusCode::kInvalidArgument;
}

inline const char* DspErrorMessage(dsp::AttitudeError e) {
  return dsp::AttitudeErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::HeadingError e) {
  return dsp::HeadingErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::HorizonStripError e) {
  return dsp::HorizonStripErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::LensError e) {
  return dsp::LensErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::StateMachineError e) {
  return dsp::StateMachineErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::SampleLutError e) {
  return dsp::SampleLutErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::SegmentationError e) {
  return dsp::SegmentationErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::SeqSlamError e) {
  return dsp::SeqSlamErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::ShError e) {
  return dsp::ShErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::StripAlignmentError e) {
  return dsp::StripAlignmentErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::Surf1dError e) {
  return dsp::Surf1dErrorMessage(e);
}
inline const char* DspErrorMessage(dsp::VanillaError e) {
  return dsp::VanillaErrorMessage(e);
}
inline const char* DspErrorMessage(const dsp::DescriptorError& e) {
  return e.message;
}

// "CONTEXT: <the error's sentence>" with the error's code; CONTEXT is printf-style.
template <typename E>
Status DspStatus(const E& error, const char* context_format, ...)
    __attribute__((format(printf, 2, 3)));

template <typename E>
Status DspStatus(const E& error, const char* context_format, ...) {
  char context[Status::kMessageCapacity];
  va_list args;
  va_start(args, context_format);
  std::vsnprintf(context, sizeof context, context_format, args);
  va_end(args);
  return Status::Error(StatusCodeOf(error), "%s: %s", context, DspErrorMessage(error));
}

}  // namespace skyloc::drivers
