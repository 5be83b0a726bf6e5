#include "skyloc/dsp/segmentation.h"

#include <cstring>

namespace skyloc::dsp {
namespace {

// Bytes from one pixel to the next, per format (YUYV: the Y of every pixel is 2 bytes on).
template <PixelFormat F>
constexpr std::size_t kPixelBytes = F == PixelFormat::kGrey8  ? 1
                                    : F == PixelFormat::kYuyv ? 2
                                                              : 3;

// The channel mean of the pixel at px, per format.
template <PixelFormat F>
inline std::uint32_t ValueOf(const std::uint8_t* px) {
  if constexpr (F == PixelFormat::kRgb24) {
    return (static_cast<std::uint32_t>(px[0]) + px[1] + px[2]) / 3u;
  } else {
    return px[0];  // grey, or YUYV's Y
  }
}

// The channel mean of pixel x of a row.
template <PixelFormat F>
inline std::uint32_t ValueAt(const std::uint8_t* row, std::int32_t x) {
  return ValueOf<F>(row + static_cast<std::size_t>(x) * kPixelBytes<F>);
}

template <PixelFormat F>
void Accumulate(const ImageView& image, std::span<const RowSpan> rows, int step,
                std::array<std::uint32_t, 4 * 256>& partial) {
  // A pointer walk with a pixel count, four partial histograms a pixel each in turn (no
  // increment waits on the one before). Indexing the member array with the pixel index
  // (partial[256 + ValueAt(row, x + s)]) made GCC rebuild every address on aarch64: 7.5
  // instructions a pixel there, 3.8 on x86-64 (docs/BENCHMARKS.md, "ARM cost, measured").
  const std::size_t stride = static_cast<std::size_t>(step) * kPixelBytes<F>;
  std::uint32_t* const h0 = partial.data();
  std::uint32_t* const h1 = h0 + 256;
  std::uint32_t* const h2 = h0 + 512;
  std::uint32_t* const h3 = h0 + 768;
  for (int y = 0; y < image.height; y += step) {
    const RowSpan span = rows[static_cast<std::size_t>(y)];
    if (span.end <= span.begin)
      continue;
    const std::uint8_t* px = image.Row(y) + static_cast<std::size_t>(span.begin) * kPixelBytes<F>;
    std::size_t n = static_cast<std::size_t>((span.end - span.begin + step - 1) / step);
    for (; n >= 4; n -= 4, px += 4 * stride) {
      ++h0[ValueOf<F>(px)];
      ++h1[ValueOf<F>(px + stride)];
      ++h2[ValueOf<F>(px + 2 * stride)];
      ++h3[ValueOf<F>(px + 3 * stride)];
    }
    for (; n > 0; --n, px += stride)
      ++h0[ValueOf<F>(px)];
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
  // Whether the frame shows sky at all is the frame's own property: judged on Otsu's split
  // also when a fixed threshold draws the line between sky and ground.
  const OtsuResult split = OtsuThreshold(histogram_);
  const bool fixed = options_.fixed_threshold >= 0;
  SegmentationResult r;
  r.sky_contrast = SeparatesSkyFromGround(split);
  r.threshold = !r.sky_contrast ? kNoSkyThreshold
                : fixed         ? options_.fixed_threshold
                                : split.threshold;
  r.separability = fixed ? 0.0 : split.separability;
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
