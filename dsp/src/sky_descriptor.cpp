#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::dsp {
namespace {

DescriptorError Fail(DescriptorError::Stage stage, const char* message) {
  return DescriptorError{stage, message};
}

}  // namespace

DescriptorError SkyDescriptor::Init(const Lens& lens, const SkyDescriptorOptions& options) {
  using Stage = DescriptorError::Stage;
  options_ = options;
  if (options_.bands < 1 || options_.bands > kMaxShBands)
    return Fail(Stage::kGrid, ShErrorMessage(ShError::kBandsOutOfRange));
  if (options_.grid.rings == 0)
    options_.grid = DefaultShGridConfig(options_.bands);
  if (const ShError e = grid_.Init(options_.grid); e != ShError::kOk)
    return Fail(Stage::kGrid, ShErrorMessage(e));
  if (const SegmentationError e = segmenter_.Init(lens, options_.segmentation);
      e != SegmentationError::kOk)
    return Fail(Stage::kSegmentation, SegmentationErrorMessage(e));
  if (const SampleLutError e = lut_.Init(lens, grid_, options_.sampling); e != SampleLutError::kOk)
    return Fail(Stage::kSampling, SampleLutErrorMessage(e));
  if (const ShError e = projector_.Init(grid_, options_.bands); e != ShError::kOk)
    return Fail(Stage::kProjection, ShErrorMessage(e));
  width_ = lens.params().width;
  height_ = lens.params().height;
  samples_.assign(grid_.sample_count(), 0.0f);
  coefficients_.assign(projector_.coefficient_count(), 0.0f);
  if (options_.path == SamplingPath::kViaMask)
    mask_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0);
  else
    mask_.clear();
  return {};
}

ImageView SkyDescriptor::mask() const {
  if (mask_.empty())
    return {};
  return {mask_.data(), width_, height_, static_cast<std::size_t>(width_), PixelFormat::kGrey8};
}

DescriptorError SkyDescriptor::Compute(const ImageView& image, std::span<float> amplitudes,
                                       SegmentationResult* segmentation) {
  using Stage = DescriptorError::Stage;
  if (amplitudes.size() != static_cast<std::size_t>(options_.bands))
    return Fail(Stage::kProjection, ShErrorMessage(ShError::kSizeMismatch));
  SegmentationResult result;
  if (options_.path == SamplingPath::kViaMask) {
    const MutableImageView mask{mask_.data(), width_, height_, static_cast<std::size_t>(width_),
                                PixelFormat::kGrey8};
    if (const SegmentationError e = segmenter_.Segment(image, mask, &result);
        e != SegmentationError::kOk)
      return Fail(Stage::kSegmentation, SegmentationErrorMessage(e));
    if (const SampleLutError e = lut_.SampleMask(mask, samples_); e != SampleLutError::kOk)
      return Fail(Stage::kSampling, SampleLutErrorMessage(e));
  } else {
    if (const SegmentationError e = segmenter_.Threshold(image, &result);
        e != SegmentationError::kOk)
      return Fail(Stage::kSegmentation, SegmentationErrorMessage(e));
    if (const SampleLutError e = lut_.SampleImage(image, result.threshold, samples_);
        e != SampleLutError::kOk)
      return Fail(Stage::kSampling, SampleLutErrorMessage(e));
  }
  if (const ShError e = projector_.Project(samples_, coefficients_); e != ShError::kOk)
    return Fail(Stage::kProjection, ShErrorMessage(e));
  if (const ShError e =
          AmplitudeSpectrum(coefficients_, options_.bands, amplitudes, options_.normalisation);
      e != ShError::kOk)
    return Fail(Stage::kProjection, ShErrorMessage(e));
  if (segmentation != nullptr)
    *segmentation = result;
  return {};
}

}  // namespace skyloc::dsp
