#include "skyloc/dsp/sky_descriptor.h"

#include <algorithm>
#include <cmath>

#include "skyloc/dsp/angles.h"

namespace skyloc::dsp {
namespace {

DescriptorError Fail(DescriptorError::Stage stage, const char* message) {
  return DescriptorError{stage, message};
}

}  // namespace

double CapElevationForTilt(double max_tilt_deg, double fov_deg) {
  return std::max(0.0, max_tilt_deg + 90.0 - std::min(90.0, fov_deg / 2.0));
}

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
  if (options_.cap.enabled) {
    const GravityCapOptions& cap = options_.cap;
    if (!(cap.elevation_deg >= 0 && cap.elevation_deg <= 85 && cap.taper_deg >= 0 &&
          cap.taper_deg <= 30 && cap.elevation_deg + cap.taper_deg < 90))
      return Fail(Stage::kSampling,
                  "gravity cap: elevation must be within 0..85 degrees, the taper within 0..30, "
                  "and their sum below 90");
    if (options_.sampling.footprint != 1)
      return Fail(Stage::kSampling,
                  "gravity cap: the world-aligned grid samples one pixel per direction; set the "
                  "sample footprint to 1");
    if (const SampleLutError e = lut_.InitOriented(lens, grid_, options_.sampling);
        e != SampleLutError::kOk)
      return Fail(Stage::kSampling, SampleLutErrorMessage(e));
    // Weight w(s) of a ring whose world elevation has sine s = cos(theta): 0 below the cap,
    // a raised cosine across the taper (in sin-elevation), 1 above.
    const double s0 = std::sin(cap.elevation_deg * kDegToRad);
    const double s1 = std::sin((cap.elevation_deg + cap.taper_deg) * kDegToRad);
    cap_weight_.resize(static_cast<std::size_t>(grid_.ring_count()));
    for (int i = 0; i < grid_.ring_count(); ++i) {
      const double e = grid_.ring(i).cos_theta;
      double w = 1.0;
      if (e <= s0)
        w = 0.0;
      else if (e < s1)
        w = 0.5 - 0.5 * std::cos((e - s0) * kPi / (s1 - s0));
      cap_weight_[static_cast<std::size_t>(i)] = static_cast<float>(w);
    }
  } else if (const SampleLutError e = lut_.Init(lens, grid_, options_.sampling);
             e != SampleLutError::kOk) {
    return Fail(Stage::kSampling, SampleLutErrorMessage(e));
  }
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
                                       SegmentationResult* segmentation, const Attitude* attitude) {
  using Stage = DescriptorError::Stage;
  if (amplitudes.size() != static_cast<std::size_t>(options_.bands))
    return Fail(Stage::kProjection, ShErrorMessage(ShError::kSizeMismatch));
  if (options_.cap.enabled) {
    const std::array<double, 3> level{0, 0, 1};
    const std::array<double, 3>& up = attitude != nullptr ? attitude->up : level;
    if (!(std::isfinite(up[0]) && std::isfinite(up[1]) && std::isfinite(up[2])) ||
        std::fabs(up[0] * up[0] + up[1] * up[1] + up[2] * up[2] - 1.0) > 1e-3)
      return Fail(Stage::kSampling, "gravity cap: the attitude's zenith is not a unit vector");
    lut_.Orient(up);
  }
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
  if (options_.cap.enabled) {
    // The world-aligned grid: what the camera cannot see continues the skyline above it,
    // then only the cap is kept.
    lut_.FillUnseenFromAbove(samples_);
    const std::size_t n_phi = static_cast<std::size_t>(grid_.longitudes());
    for (std::size_t i = 0; i < cap_weight_.size(); ++i) {
      const float w = cap_weight_[i];
      if (w == 1.0f)
        continue;
      float* ring = samples_.data() + i * n_phi;
      for (std::size_t j = 0; j < n_phi; ++j)
        ring[j] *= w;
    }
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
