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
#include "skyloc/dsp/imu.h"
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

// The gravity-aligned cap (docs/SKY_DESCRIPTOR.md, "Tilt"). The amplitude spectrum is
// rotation-invariant only for the whole sphere; a tilted lens crops a different part of the
// sky, so the hemisphere's spectrum changes with the tilt. With the zenith known (from the
// attitude), the descriptor keeps only the sky above `elevation_deg` in the *world* frame,
// weighted by a raised-cosine taper over `taper_deg` (a hard edge on the camera's grid would
// alias differently at each tilt). That cap is a function of world elevation only, so its
// spectrum is the same at any tilt as long as the whole cap is in view:
//   elevation_deg >= max_tilt_deg + 90 - min(90, fov_deg / 2)       (CapElevationForTilt)
// Cost per frame: one dot product and a compare per sample.
struct GravityCapOptions {
  bool enabled = false;
  double elevation_deg = 60;  // world elevation of the cap's lower edge, 0..85
  double taper_deg = 10;      // the weight rises from 0 to 1 over this many degrees, 0..30
};

// The lowest cap elevation that stays in view at tilts up to max_tilt_deg for a lens whose
// full field of view is fov_deg (the upper hemisphere grid also limits it to 90 degrees
// from the body zenith). Clamped to 0.
double CapElevationForTilt(double max_tilt_deg, double fov_deg);

struct SkyDescriptorOptions {
  int bands = 120;
  // Rings 0 = DefaultShGridConfig(bands) (unaliased); PaperShGridConfig() for the paper.
  ShGridConfig grid{0, 0, ShCoverage::kUpperHemisphere};
  SegmentationOptions segmentation;
  SampleLutOptions sampling;
  SamplingPath path = SamplingPath::kDirect;
  AmplitudeNormalisation normalisation = AmplitudeNormalisation::kNone;
  GravityCapOptions cap;
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
  // attitude: the body's zenith for the gravity-aligned cap (options.cap.enabled); null
  // means "assume level" (the cap about the body's own z axis: what a robot without a
  // working attitude source can still compare with a route taught level). Ignored when the
  // cap is off.
  DescriptorError Compute(const ImageView& image, std::span<float> amplitudes,
                          SegmentationResult* segmentation = nullptr,
                          const Attitude* attitude = nullptr);

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
  void ApplyCap(const std::array<double, 3>& up);

  std::vector<float> samples_;
  std::vector<float> coefficients_;
  // The cap: per longitude (cos phi, sin phi) and per ring (sin theta, cos theta).
  std::vector<float> cos_phi_, sin_phi_, ring_sin_, ring_cos_, along_phi_;
  std::vector<std::uint8_t> mask_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace skyloc::dsp
