// The sky descriptor of one frame (paper section III): sky segmentation (channel mean,
// Otsu) -> grid samples through the lens lookup table -> real spherical harmonics ->
// amplitude spectrum a_l, l = 0..bands-1. Init() allocates everything (histogram, lookup
// table, samples, coefficients, projector tables); Compute() allocates nothing.
//
//   SkyDescriptor descriptor;
//   if (auto e = descriptor.Init(lens, SkyDescriptorOptions{}); !e.ok()) ... e.message
//   descriptor.Compute(frame.image, amplitudes, &segmentation);
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sample_lut.h"
#include "skyloc/dsp/segmentation.h"
#include "skyloc/dsp/sh_grid.h"
#include "skyloc/dsp/spherical_harmonics.h"

namespace skyloc::dsp {

enum class SamplingPath : std::uint8_t {
  // Threshold the frame at the sample pixels only (default: ~15k reads instead of writing
  // a full mask; same samples, see the SampleLut tests).
  kDirect,
  // Write the full binary mask first, then sample it (tools that also save the mask).
  kViaMask,
};

struct SkyDescriptorOptions {
  int bands = 120;
  // Rings 0 = DefaultShGridConfig(bands) (unaliased); PaperShGridConfig() for the paper.
  ShGridConfig grid{0, 0, ShCoverage::kUpperHemisphere};
  SegmentationOptions segmentation;
  SampleLutOptions sampling;
  SamplingPath path = SamplingPath::kDirect;
  AmplitudeNormalisation normalisation = AmplitudeNormalisation::kNone;
};

// Which stage rejected the configuration or the frame, and a sentence saying why.
struct DescriptorError {
  enum class Stage : std::uint8_t { kNone, kGrid, kSegmentation, kSampling, kProjection };
  Stage stage = Stage::kNone;
  const char* message = "ok";
  bool ok() const { return stage == Stage::kNone; }
};

class SkyDescriptor {
 public:
  // The lens must be initialised; it is only used here, not kept.
  DescriptorError Init(const Lens& lens, const SkyDescriptorOptions& options);

  // amplitudes: bands() values. segmentation (optional): threshold and sky fraction.
  DescriptorError Compute(const ImageView& image, std::span<float> amplitudes,
                          SegmentationResult* segmentation = nullptr);

  int bands() const { return options_.bands; }
  const ShGrid& grid() const { return grid_; }
  const SampleLut& lut() const { return lut_; }
  // The last frame's samples (ring-major) and SH coefficients, for tools and tests.
  std::span<const float> samples() const { return samples_; }
  std::span<const float> coefficients() const { return coefficients_; }
  // The last frame's mask (kViaMask only; empty otherwise).
  ImageView mask() const;

 private:
  SkyDescriptorOptions options_;
  ShGrid grid_;
  SkySegmenter segmenter_;
  SampleLut lut_;
  ShProjector projector_;
  std::vector<float> samples_;
  std::vector<float> coefficients_;
  std::vector<std::uint8_t> mask_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace skyloc::dsp
