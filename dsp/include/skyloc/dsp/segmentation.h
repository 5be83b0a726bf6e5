// Sky segmentation (paper section III-A): the mean of the colour channels, a 256-bin
// histogram over the pixels inside the image circle, Otsu's threshold (or a fixed one),
// and a binary mask. Pixels outside the image circle are ground.
//
// Per-pixel value: GREY as is; RGB24/BGR24 the integer mean (R + G + B) / 3; YUYV the Y
// byte. The image circle comes from the lens: Init() records, per row, the run of
// columns whose pixel centre is visible, so the frame path only walks those runs.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/otsu.h"

namespace skyloc::dsp {

// Mask values written by SkySegmenter::Segment.
inline constexpr std::uint8_t kMaskSky = 255;
inline constexpr std::uint8_t kMaskGround = 0;

// Columns [begin, end) of one row that lie inside the image circle (begin == end: none).
struct RowSpan {
  std::int32_t begin = 0;
  std::int32_t end = 0;
};

struct SegmentationOptions {
  // -1: Otsu's threshold on every frame. 0..254: this fixed threshold. Pixels whose value
  // is greater than the threshold are sky.
  int fixed_threshold = -1;
  // Histogram every n-th row and column (1 = every pixel). Larger steps make the
  // histogram (and the sky fraction reported from it) an estimate, for speed.
  int histogram_step = 1;
};

// A frame whose pixels do not split into two classes (sky and ground) shows no sky: lens
// cap on, a saturated sensor, fog, a uniform grey. Its threshold is then kNoSkyThreshold,
// so the mask is all ground and the sky fraction 0, and `sky_contrast` says so; what it
// describes is no place (the firmware does not match it).
inline constexpr int kNoSkyThreshold = 255;

struct SegmentationResult {
  int threshold = 0;
  // Otsu's between-class / total variance (0..1); 0 with a fixed threshold.
  double separability = 0.0;
  // The pixels split into sky and ground (dsp::SeparatesSkyFromGround, otsu.h).
  bool sky_contrast = false;
  // Sky pixels / pixels inside the image circle (from the histogram).
  double sky_fraction = 0.0;
  std::uint32_t circle_pixels = 0;  // pixels the histogram counted
};

enum class SegmentationError : std::uint8_t {
  kOk,
  kBadOptions,     // fixed_threshold outside -1..254 or histogram_step < 1
  kSizeMismatch,   // the frame (or mask) is not the size the segmenter was built for
  kBadMaskFormat,  // the mask must be kGrey8
};

const char* SegmentationErrorMessage(SegmentationError error);

// The per-pixel channel mean of one pixel (for tests and tools; the frame path uses
// specialised loops).
std::uint8_t PixelValue(const ImageView& image, int x, int y);

class SkySegmenter {
 public:
  // Scans the lens's visible pixels once and allocates the row runs. Not for the frame path.
  SegmentationError Init(const Lens& lens, const SegmentationOptions& options);

  // Histogram + threshold + sky fraction, without writing a mask (the sample table can
  // threshold the image directly). Allocates nothing.
  SegmentationError Threshold(const ImageView& image, SegmentationResult* result);
  // Threshold() and the full binary mask (kGrey8, kMaskSky / kMaskGround, caller-owned).
  SegmentationError Segment(const ImageView& image, const MutableImageView& mask,
                            SegmentationResult* result);

  const Histogram256& histogram() const { return histogram_; }
  std::span<const RowSpan> rows() const { return rows_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  SegmentationOptions options_;
  int width_ = 0;
  int height_ = 0;
  std::vector<RowSpan> rows_;
  Histogram256 histogram_{};
  // Four interleaved partial histograms: consecutive equal pixels (common in sky) would
  // otherwise serialise on one counter.
  std::array<std::uint32_t, 4 * 256> partial_{};
};

}  // namespace skyloc::dsp
