#include "skyloc/dsp/horizon_strip.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "skyloc/dsp/angles.h"

namespace skyloc::dsp {

const char* HorizonStripErrorMessage(HorizonStripError error) {
  switch (error) {
    case HorizonStripError::kOk:
      return "ok";
    case HorizonStripError::kBadOptions:
      return "horizon strip options out of range: n_azimuth must be 8..65536, band_rows "
             "1..256, and the elevation band within [-90, 90] degrees with min <= max";
    case HorizonStripError::kNotVisible:
      return "the camera sees none of the horizon band: lower the band's elevations or "
             "check the lens field of view and mount angles";
    case HorizonStripError::kSizeMismatch:
      return "the frame is not the image size the lens was configured for: fix the camera "
             "file's width/height or the capture size";
    case HorizonStripError::kBadOutputSize:
      return "the strip buffer must hold exactly n_azimuth values";
  }
  return "unknown horizon strip error";
}

HorizonStripError StripToBytes(std::span<const float> strip, std::span<std::uint8_t> bytes) {
  if (bytes.size() != strip.size())
    return HorizonStripError::kBadOutputSize;
  for (std::size_t j = 0; j < strip.size(); ++j)
    bytes[j] = static_cast<std::uint8_t>(std::lround(std::clamp(strip[j], 0.0f, 255.0f)));
  return HorizonStripError::kOk;
}

HorizonStripError PackStrip(std::span<const std::uint8_t> bytes, std::span<std::uint8_t> packed) {
  if (packed.size() != PackedStripBytes(bytes.size()))
    return HorizonStripError::kBadOutputSize;
  std::uint8_t lo = 255;
  std::uint8_t hi = 0;
  for (const std::uint8_t v : bytes) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (bytes.empty())
    lo = hi = 0;
  const unsigned width = static_cast<unsigned>(hi - lo) + 1u;  // byte values in the range
  packed[0] = lo;
  packed[1] = static_cast<std::uint8_t>(hi - lo);
  std::fill(packed.begin() + 2, packed.end(), std::uint8_t{0});
  for (std::size_t j = 0; j < bytes.size(); ++j) {
    // (v - lo + 0.5) * 16 / width in integers: below 16 since v - lo < width.
    const unsigned level = ((2u * static_cast<unsigned>(bytes[j] - lo) + 1u) * 8u) / width;
    packed[2 + j / 2] |= static_cast<std::uint8_t>(level << (4u * (j % 2)));
  }
  return HorizonStripError::kOk;
}

HorizonStripError UnpackStrip(std::span<const std::uint8_t> packed, std::span<float> strip) {
  if (packed.size() != PackedStripBytes(strip.size()))
    return HorizonStripError::kBadOutputSize;
  const int lo = packed[0];
  const int width = packed[1] + 1;
  // The 16 centres once, then a look-up a column (a third of the instructions of the
  // arithmetic per column): lo - 0.5 + (2 level + 1) width / 32, an integer over 32, exact
  // in float.
  float centre[16];
  for (int level = 0; level < 16; ++level)
    centre[level] = static_cast<float>(32 * lo - 16 + (2 * level + 1) * width) / 32.0f;
  const std::size_t pairs = strip.size() / 2;
  for (std::size_t i = 0; i < pairs; ++i) {
    const std::uint8_t b = packed[2 + i];
    strip[2 * i] = centre[b & 15u];
    strip[2 * i + 1] = centre[b >> 4];
  }
  if (strip.size() % 2 == 1)
    strip.back() = centre[packed[2 + pairs] & 15u];
  return HorizonStripError::kOk;
}

HorizonStripError HorizonStrip::Init(const Lens& lens, const HorizonStripOptions& options) {
  const bool band_ok = std::isfinite(options.elevation_min_deg) &&
                       std::isfinite(options.elevation_max_deg) &&
                       options.elevation_min_deg >= -90.0 && options.elevation_max_deg <= 90.0 &&
                       options.elevation_min_deg <= options.elevation_max_deg;
  if (options.n_azimuth < 8 || options.n_azimuth > 65536 || options.band_rows < 1 ||
      options.band_rows > 256 || !band_ok) {
    return HorizonStripError::kBadOptions;
  }
  const int width = lens.params().width;
  const int height = lens.params().height;
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535) {
    return HorizonStripError::kSizeMismatch;
  }

  const auto n = static_cast<std::size_t>(options.n_azimuth);
  std::vector<Tap> taps;
  taps.reserve(n * static_cast<std::size_t>(options.band_rows));
  std::vector<std::uint32_t> column_end(n);
  std::vector<float> column_weight(n);
  int empty = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double phi =
        2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(options.n_azimuth);
    std::uint32_t visible = 0;
    for (int r = 0; r < options.band_rows; ++r) {
      // Row centres spread evenly over the band (a single row sits in its middle).
      const double t = (static_cast<double>(r) + 0.5) / static_cast<double>(options.band_rows);
      const double elevation = (options.elevation_min_deg +
                                t * (options.elevation_max_deg - options.elevation_min_deg)) *
                               kDegToRad;
      const Eigen::Vector3d ray(std::cos(elevation) * std::cos(phi),
                                std::cos(elevation) * std::sin(phi), std::sin(elevation));
      double x = 0.0;
      double y = 0.0;
      if (!lens.RayToPixel(ray, &x, &y))
        continue;
      const double xi = std::floor(x + 0.5);
      const double yi = std::floor(y + 0.5);
      if (xi < 0.0 || yi < 0.0 || xi > width - 1 || yi > height - 1)
        continue;
      taps.push_back({static_cast<std::uint16_t>(xi), static_cast<std::uint16_t>(yi)});
      ++visible;
    }
    column_end[j] = static_cast<std::uint32_t>(taps.size());
    column_weight[j] = visible > 0 ? 1.0f / static_cast<float>(visible) : 0.0f;
    if (visible == 0)
      ++empty;
  }
  if (taps.empty())
    return HorizonStripError::kNotVisible;

  options_ = options;
  width_ = width;
  height_ = height;
  n_azimuth_ = options.n_azimuth;
  empty_columns_ = empty;
  visible_fraction_ =
      static_cast<double>(taps.size()) / (static_cast<double>(n) * options.band_rows);
  taps_ = std::move(taps);
  column_end_ = std::move(column_end);
  column_weight_ = std::move(column_weight);
  return HorizonStripError::kOk;
}

template <PixelFormat kFormat>
void HorizonStrip::Gather(const ImageView& image, std::span<float> strip) const {
  std::uint32_t begin = 0;
  for (std::size_t j = 0; j < strip.size(); ++j) {
    const std::uint32_t end = column_end_[j];
    std::uint32_t sum = 0;  // 256 taps x 255 fits easily
    for (std::uint32_t k = begin; k < end; ++k) {
      const Tap tap = taps_[k];
      const std::uint8_t* row = image.Row(tap.y);
      if constexpr (kFormat == PixelFormat::kGrey8) {
        sum += row[tap.x];
      } else if constexpr (kFormat == PixelFormat::kYuyv) {
        sum += row[2u * tap.x];
      } else {
        const std::uint8_t* p = row + 3u * tap.x;
        sum += (static_cast<std::uint32_t>(p[0]) + p[1] + p[2]) / 3u;
      }
    }
    strip[j] = static_cast<float>(sum) * column_weight_[j];
    begin = end;
  }
}

HorizonStripError HorizonStrip::Extract(const ImageView& image, std::span<float> strip) const {
  if (image.empty() || image.width != width_ || image.height != height_ ||
      image.stride < image.RowBytes()) {
    return HorizonStripError::kSizeMismatch;
  }
  if (n_azimuth_ == 0 || strip.size() != static_cast<std::size_t>(n_azimuth_)) {
    return HorizonStripError::kBadOutputSize;
  }
  switch (image.format) {
    case PixelFormat::kGrey8:
      Gather<PixelFormat::kGrey8>(image, strip);
      break;
    case PixelFormat::kRgb24:
      Gather<PixelFormat::kRgb24>(image, strip);
      break;
    case PixelFormat::kBgr24:
      Gather<PixelFormat::kBgr24>(image, strip);
      break;
    case PixelFormat::kYuyv:
      Gather<PixelFormat::kYuyv>(image, strip);
      break;
  }
  return HorizonStripError::kOk;
}

}  // namespace skyloc::dsp
