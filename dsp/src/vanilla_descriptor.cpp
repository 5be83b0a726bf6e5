#include "skyloc/dsp/vanilla_descriptor.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace skyloc::dsp {
namespace {

// The source interval [o * scale, (o + 1) * scale) of output pixel o, as the first and
// last source pixel it touches and the fraction of those two that it covers.
struct Span1d {
  int first = 0;
  int last = 0;
  double first_weight = 1.0;  // coverage of `first` (1 when fully inside)
  double last_weight = 1.0;   // coverage of `last`
};

Span1d AreaSpan(int o, int out_size, int in_size) {
  const double scale = static_cast<double>(in_size) / out_size;
  const double a = o * scale, b = (o + 1) * scale;
  Span1d s;
  s.first = static_cast<int>(std::floor(a));
  s.last = std::min(in_size - 1, static_cast<int>(std::ceil(b)) - 1);
  if (s.first == s.last) {
    s.first_weight = s.last_weight = b - a;
  } else {
    s.first_weight = (s.first + 1) - a;
    s.last_weight = b - s.last;
  }
  return s;
}

double Weight(const Span1d& s, int i) {
  if (i == s.first)
    return s.first_weight;
  if (i == s.last)
    return s.last_weight;
  return 1.0;
}

}  // namespace

const char* VanillaErrorMessage(VanillaError error) {
  switch (error) {
    case VanillaError::kOk:
      return "ok";
    case VanillaError::kEmptyImage:
      return "image is empty or its stride is shorter than a row";
    case VanillaError::kBadOutputSize:
      return "vanilla descriptor output must hold 64 x 32 values";
  }
  return "unknown vanilla descriptor error";
}

float PixelLuminance(const ImageView& image, int x, int y) {
  const std::uint8_t* row = image.Row(y);
  const std::size_t xs = static_cast<std::size_t>(x);
  switch (image.format) {
    case PixelFormat::kGrey8:
      return row[xs];
    case PixelFormat::kRgb24:
      return 0.299f * row[3 * xs] + 0.587f * row[3 * xs + 1] + 0.114f * row[3 * xs + 2];
    case PixelFormat::kBgr24:
      return 0.299f * row[3 * xs + 2] + 0.587f * row[3 * xs + 1] + 0.114f * row[3 * xs];
    case PixelFormat::kYuyv:
      return row[2 * xs];
  }
  return 0.0f;
}

bool AreaResizeLuminance(const ImageView& image, int out_width, int out_height,
                         std::span<float> out) {
  if (image.empty() || image.stride < image.RowBytes() || out_width < 1 || out_height < 1 ||
      out.size() != static_cast<std::size_t>(out_width) * static_cast<std::size_t>(out_height))
    return false;
  const double cell_area = (static_cast<double>(image.width) / out_width) *
                           (static_cast<double>(image.height) / out_height);
  for (int oy = 0; oy < out_height; ++oy) {
    const Span1d sy = AreaSpan(oy, out_height, image.height);
    for (int ox = 0; ox < out_width; ++ox) {
      const Span1d sx = AreaSpan(ox, out_width, image.width);
      double sum = 0.0;
      for (int y = sy.first; y <= sy.last; ++y) {
        double row_sum = 0.0;
        for (int x = sx.first; x <= sx.last; ++x)
          row_sum += Weight(sx, x) * static_cast<double>(PixelLuminance(image, x, y));
        sum += Weight(sy, y) * row_sum;
      }
      out[static_cast<std::size_t>(oy * out_width + ox)] = static_cast<float>(sum / cell_area);
    }
  }
  return true;
}

VanillaError VanillaDescriptor(const ImageView& image, std::span<float> out) {
  if (out.size() != static_cast<std::size_t>(kVanillaDescriptorSize))
    return VanillaError::kBadOutputSize;
  if (image.empty() || image.stride < image.RowBytes())
    return VanillaError::kEmptyImage;
  AreaResizeLuminance(image, kVanillaWidth, kVanillaHeight, out);
  // Patch normalisation (OpenSeqSLAM patchNormalize, mode 1): z-scores within each 8x8
  // patch, sample std as MATLAB's std. A flat patch has nothing to normalise: zeros.
  constexpr int kN = kVanillaPatch * kVanillaPatch;
  for (int py = 0; py < kVanillaHeight; py += kVanillaPatch) {
    for (int px = 0; px < kVanillaWidth; px += kVanillaPatch) {
      auto at = [&](int i) -> float& {
        return out[static_cast<std::size_t>((py + i / kVanillaPatch) * kVanillaWidth + px +
                                            i % kVanillaPatch)];
      };
      double mean = 0.0;
      for (int i = 0; i < kN; ++i)
        mean += static_cast<double>(at(i));
      mean /= kN;
      double ss = 0.0;
      for (int i = 0; i < kN; ++i) {
        const double dv = static_cast<double>(at(i)) - mean;
        ss += dv * dv;
      }
      const double sd = std::sqrt(ss / (kN - 1));
      // Below 1e-6 grey levels the patch is flat up to rounding of the averaging.
      const bool flat = !(sd > 1e-6);
      for (int i = 0; i < kN; ++i)
        at(i) = flat ? 0.0f : static_cast<float>((static_cast<double>(at(i)) - mean) / sd);
    }
  }
  return VanillaError::kOk;
}

float SumAbsoluteDifference(std::span<const float> a, std::span<const float> b) {
  const std::size_t n = std::min(a.size(), b.size());
  float sum = 0.0f;
  for (std::size_t i = 0; i < n; ++i)
    sum += std::fabs(a[i] - b[i]);
  return sum;
}

}  // namespace skyloc::dsp
