// The one mapping from dsp's error values to a Status: every caller of dsp (the pipeline,
// the frame loop, the tools) turns a dsp error into the same code and the same sentence,
// prefixed with what it was doing:
//   if (e != dsp::SeqSlamError::kOk) return DspStatus(e, "[seqslam]");
// dsp itself stays free of platform/ (tests/lint): its errors are plain enums with a
// message function each, and this header is where they meet Status.
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

namespace skyloc::firmware {

// The code of each dsp error: a wrong parameter or size is kInvalidArgument, a call in the
// wrong state kFailedPrecondition, a full fixed buffer kResourceExhausted, input that
// carries nothing to measure kDataLoss.
StatusCode StatusCodeOf(dsp::AttitudeError e);
StatusCode StatusCodeOf(dsp::HeadingError e);
StatusCode StatusCodeOf(dsp::HorizonStripError e);
StatusCode StatusCodeOf(dsp::LensError e);
StatusCode StatusCodeOf(dsp::StateMachineError e);
StatusCode StatusCodeOf(dsp::SampleLutError e);
StatusCode StatusCodeOf(dsp::SegmentationError e);
StatusCode StatusCodeOf(dsp::SeqSlamError e);
StatusCode StatusCodeOf(dsp::ShError e);
StatusCode StatusCodeOf(dsp::StripAlignmentError e);
StatusCode StatusCodeOf(dsp::Surf1dError e);
StatusCode StatusCodeOf(dsp::VanillaError e);
// A descriptor that failed at start-up (Init: its options) or on a frame (Compute: the
// frame is not what the descriptor was built for) has the same stages; kInvalidArgument.
StatusCode StatusCodeOf(const dsp::DescriptorError& e);

const char* DspErrorMessage(dsp::AttitudeError e);
const char* DspErrorMessage(dsp::HeadingError e);
const char* DspErrorMessage(dsp::HorizonStripError e);
const char* DspErrorMessage(dsp::LensError e);
const char* DspErrorMessage(dsp::StateMachineError e);
const char* DspErrorMessage(dsp::SampleLutError e);
const char* DspErrorMessage(dsp::SegmentationError e);
const char* DspErrorMessage(dsp::SeqSlamError e);
const char* DspErrorMessage(dsp::ShError e);
const char* DspErrorMessage(dsp::StripAlignmentError e);
const char* DspErrorMessage(dsp::Surf1dError e);
const char* DspErrorMessage(dsp::VanillaError e);
const char* DspErrorMessage(const dsp::DescriptorError& e);

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

}  // namespace skyloc::firmware
