#include "skyloc/dsp/segmentation.h"

#include <cstring>

namespace skyloc::dsp {
namespace {

// The channel mean of pixel x of a row, per format.
template <PixelFormat F>
inline std::uint32_t ValueAt(const std::uint8_t* row, std::int32_t x) {
  const auto i = static_cast<std::size_t>(x);
  if constexpr (F == PixelFormat::kGrey8) {
    return row[i];
  } else if constexpr (F == PixelFormat::kYuyv) {
    return row[2 * i];
  } else {
    return (static_cast<std::uint32_t>(row[3 * i]) + row[3 * i + 1] + row[3 * i + 2]) / 3u;
  }
}

template <PixelFormat F>
void Accumulate(const ImageView& image, std::span<const RowSpan> rows, int step,
                std::array<std::uint32_t, 4 * 256>& partial) {
  const auto s = static_cast<std::int32_t>(step);
  for (int y = 0; y < image.height; y += step) {
    const RowSpan span = rows[static_cast<std::size_t>(y)];
    const std::uint8_t* row = image.Row(y);
    std::int32_t x = span.begin;
    for (; x + 3 * s < span.end; x += 4 * s) {
      ++partial[ValueAt<F>(row, x)];
      ++partial[256 + ValueAt<F>(row, x + s)];
      ++partial[512 + ValueAt<F>(row, x + 2 * s)];
      ++partial[768 + ValueAt<F>(row, x + 3 * s)];
    }
    for (; x < span.end; x += s)
      ++partial[ValueAt<F>(row, x)];
  }
}

template <PixelFormat F>
void WriteMask(const ImageView& image, std::span<const RowSpan> rows, int threshold,
               const MutableImageView& mask) {
  const auto t = static_cast<std::uint32_t>(threshold);
  const auto width = static_cast<std::size_t>(image.width);
  for (int y = 0; y < image.height; ++y) {
    const RowSpan span = rows[static_cast<std::size_t>(y)];
    const std::uint8_t* row = image.Row(y);
    std::uint8_t* out = mask.Row(y);
    const auto begin = static_cast<std::size_t>(span.begin);
    const auto end = static_cast<std::size_t>(span.end);
    std::memset(out, kMaskGround, begin);
    for (std::int32_t x = span.begin; x < span.end; ++x)
      out[static_cast<std::size_t>(x)] = ValueAt<F>(row, x) > t ? kMaskSky : kMaskGround;
    std::memset(out + end, kMaskGround, width - end);
  }
}

}  // namespace

const char* SegmentationErrorMessage(SegmentationError error) {
  switch (error) {
    case SegmentationError::kOk:
      return "ok";
    case SegmentationError::kBadOptions:
      return "the fixed threshold must be -1 (Otsu) or 0..254, and the histogram step >= 1";
    case SegmentationError::kSizeMismatch:
      return "the frame is not the size the camera file describes: fix width/height there";
    case SegmentationError::kBadMaskFormat:
      return "the sky mask must be an 8-bit grey image of the frame's size";
  }
  return "unknown segmentation error";
}

std::uint8_t PixelValue(const ImageView& image, int x, int y) {
  const std::uint8_t* row = image.Row(y);
  switch (image.format) {
    case PixelFormat::kGrey8:
      return static_cast<std::uint8_t>(ValueAt<PixelFormat::kGrey8>(row, x));
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      return static_cast<std::uint8_t>(ValueAt<PixelFormat::kRgb24>(row, x));
    case PixelFormat::kYuyv:
      return static_cast<std::uint8_t>(ValueAt<PixelFormat::kYuyv>(row, x));
  }
  return 0;
}

SegmentationError SkySegmenter::Init(const Lens& lens, const SegmentationOptions& options) {
  if (options.fixed_threshold < -1 || options.fixed_threshold > 254 || options.histogram_step < 1)
    return SegmentationError::kBadOptions;
  options_ = options;
  width_ = lens.params().width;
  height_ = lens.params().height;
  rows_.assign(static_cast<std::size_t>(height_), RowSpan{});
  // The visible region of every model is convex along a row (a disc clipped by the image),
  // so each row is one run: scan in from both ends.
  Eigen::Vector3d ray;
  for (int y = 0; y < height_; ++y) {
    std::int32_t begin = 0;
    while (begin < width_ && !lens.PixelToCameraRay(begin, y, &ray))
      ++begin;
    std::int32_t end = width_;
    while (end > begin && !lens.PixelToCameraRay(end - 1, y, &ray))
      --end;
    rows_[static_cast<std::size_t>(y)] = {begin, end};
  }
  return SegmentationError::kOk;
}

SegmentationError SkySegmenter::Threshold(const ImageView& image, SegmentationResult* result) {
  if (image.width != width_ || image.height != height_ || image.data == nullptr)
    return SegmentationError::kSizeMismatch;
  partial_.fill(0);
  const int step = options_.histogram_step;
  switch (image.format) {
    case PixelFormat::kGrey8:
      Accumulate<PixelFormat::kGrey8>(image, rows_, step, partial_);
      break;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      Accumulate<PixelFormat::kRgb24>(image, rows_, step, partial_);
      break;
    case PixelFormat::kYuyv:
      Accumulate<PixelFormat::kYuyv>(image, rows_, step, partial_);
      break;
  }
  std::uint64_t total = 0;
  for (std::size_t v = 0; v < 256; ++v) {
    histogram_[v] = partial_[v] + partial_[256 + v] + partial_[512 + v] + partial_[768 + v];
    total += histogram_[v];
  }
  SegmentationResult r;
  if (options_.fixed_threshold >= 0) {
    r.threshold = options_.fixed_threshold;
  } else {
    const OtsuResult otsu = OtsuThreshold(histogram_);
    r.threshold = otsu.threshold;
    r.separability = otsu.separability;
  }
  std::uint64_t sky = 0;
  for (std::size_t v = static_cast<std::size_t>(r.threshold) + 1; v < 256; ++v)
    sky += histogram_[v];
  r.circle_pixels = static_cast<std::uint32_t>(total);
  r.sky_fraction = total > 0 ? static_cast<double>(sky) / static_cast<double>(total) : 0.0;
  *result = r;
  return SegmentationError::kOk;
}

SegmentationError SkySegmenter::Segment(const ImageView& image, const MutableImageView& mask,
                                        SegmentationResult* result) {
  if (mask.format != PixelFormat::kGrey8 || mask.width != width_ || mask.height != height_ ||
      mask.data == nullptr)
    return SegmentationError::kBadMaskFormat;
  const SegmentationError e = Threshold(image, result);
  if (e != SegmentationError::kOk)
    return e;
  switch (image.format) {
    case PixelFormat::kGrey8:
      WriteMask<PixelFormat::kGrey8>(image, rows_, result->threshold, mask);
      break;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      WriteMask<PixelFormat::kRgb24>(image, rows_, result->threshold, mask);
      break;
    case PixelFormat::kYuyv:
      WriteMask<PixelFormat::kYuyv>(image, rows_, result->threshold, mask);
      break;
  }
  return SegmentationError::kOk;
}

}  // namespace skyloc::dsp
