// Non-owning views of 8-bit images, as cameras and files deliver them. The pixel memory
// belongs to whoever produced it (a driver's mmap'ed buffer, a decoded file).
#pragma once

#include <cstddef>
#include <cstdint>

namespace skyloc::dsp {

enum class PixelFormat : std::uint8_t {
  kGrey8,  // one byte a pixel (V4L2 GREY)
  kRgb24,  // R, G, B bytes (V4L2 RGB24, decoded PNG)
  kBgr24,  // B, G, R bytes in memory (V4L2 BGR24; note libcamera's BGR888 is R, G, B in memory =
           // kRgb24)
  kYuyv,   // Y0 U Y1 V for two pixels (V4L2 YUYV); Y is the luminance the segmenter uses
};

constexpr int BytesPerPixelTimes2(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey8:
      return 2;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      return 6;
    case PixelFormat::kYuyv:
      return 4;
  }
  return 0;
}

const char* PixelFormatName(PixelFormat f);

struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::size_t stride = 0;  // bytes from one row to the next
  PixelFormat format = PixelFormat::kGrey8;

  const std::uint8_t* Row(int y) const { return data + static_cast<std::size_t>(y) * stride; }
  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  // Bytes one row of pixels occupies (the stride may be larger).
  std::size_t RowBytes() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(BytesPerPixelTimes2(format)) /
           2;
  }
};

struct MutableImageView {
  std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::size_t stride = 0;
  PixelFormat format = PixelFormat::kGrey8;

  std::uint8_t* Row(int y) const { return data + static_cast<std::size_t>(y) * stride; }
  operator ImageView() const { return {data, width, height, stride, format}; }  // NOLINT
};

}  // namespace skyloc::dsp
