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
// attitude), the descriptor samples its grid in the *world* frame (SampleLut::Orient: each
// world direction read bilinearly where the tilted lens sees it) and keeps only the sky
// above `elevation_deg`, weighted by a raised-cosine taper over `taper_deg` (a hard edge
// would alias). That cap is a function of world direction only, so its spectrum is the
// same at any tilt as long as the whole cap is in view:
//   elevation_deg >= max_tilt_deg + 90 - min(90, fov_deg / 2)       (CapElevationForTilt)
// Tilted further, the part of the cap below the lens's view takes the value of the nearest
// seen direction above it (SampleLut::FillUnseenFromAbove, the skyline model): exact where
// the skyline is above the view's edge, a guess where it falls through the unseen band.
// Cost per frame: a rotation, a table read and a 2 x 2 pixel read per sample.
struct GravityCapOptions {
  bool enabled = false;
  double elevation_deg = 60;  // world elevation of the cap's lower edge, 0..85
  double taper_deg = 10;      // the weight rises from 0 to 1 over this many degrees, 0..30
};

// The lowest cap elevation that stays in view at tilts up to max_tilt_deg for a lens whose
// full field of view is fov_deg, counting the view to at most 90 degrees from the body
// zenith (the rule of the body-frame grid before the world-aligned one; kept so that the
// configured caps and the routes taught with them stay what they were; a wider lens's
// extra degrees are still read, not filled). Clamped to 0.
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

  std::vector<float> samples_;
  std::vector<float> coefficients_;
  // The cap: the weight of each ring of the world-aligned grid.
  std::vector<float> cap_weight_;
  std::vector<std::uint8_t> mask_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace skyloc::dsp
