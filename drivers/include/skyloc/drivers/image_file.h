// Image files for the tools (describe, simulate, evaluate, replay): PNG and binary
// PGM (P5) / PPM (P6) in, PNG out. PNG goes through Debian's stb; PNM is read directly
// (stb mishandles 16-bit PNM). Not for the frame path: loading
// allocates the image it returns.
#pragma once

#include <cstdint>
#include <memory>

#include "skyloc/dsp/image.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// An image that owns its pixels (8-bit grey or RGB, rows packed: stride = width * channels).
class OwnedImage {
 public:
  OwnedImage() = default;
  OwnedImage(OwnedImage&&) noexcept = default;
  OwnedImage& operator=(OwnedImage&&) noexcept = default;
  OwnedImage(const OwnedImage&) = delete;
  OwnedImage& operator=(const OwnedImage&) = delete;

  // Zero-filled image; format kGrey8, kRgb24 or kBgr24 (kYuyv needs an even width).
  static Result<OwnedImage> Allocate(int width, int height, dsp::PixelFormat format);

  dsp::ImageView view() const { return {pixels_.get(), width_, height_, stride_, format_}; }
  dsp::MutableImageView mutable_view() {
    return {pixels_.get(), width_, height_, stride_, format_};
  }
  int width() const { return width_; }
  int height() const { return height_; }
  dsp::PixelFormat format() const { return format_; }
  bool empty() const { return pixels_ == nullptr; }

 private:
  std::unique_ptr<std::uint8_t[]> pixels_;
  int width_ = 0;
  int height_ = 0;
  std::size_t stride_ = 0;
  dsp::PixelFormat format_ = dsp::PixelFormat::kGrey8;
};

// Loads a PNG (1/2/4/8/16 bit, grey, grey+alpha, RGB, RGBA) or a binary PGM/PPM (any
// maxval up to 65535) as kGrey8 (grey inputs) or kRgb24 (colour inputs). Alpha is dropped;
// 16-bit and other maxvals are scaled to 0..255. Errors name the file and say what is
// wrong: kNotFound (no such file), kPermissionDenied, kInvalidArgument (not a supported
// image, or a corrupt one).
Result<OwnedImage> LoadImage(const char* path);

// Writes a PNG: kGrey8 as grey, kRgb24/kBgr24 as RGB, kYuyv as its grey Y plane. The data
// goes to a temporary file in the same directory that is renamed over `path` only once it
// is complete, so a crash never leaves half an image under the final name.
Status SavePng(const char* path, dsp::ImageView image);

}  // namespace skyloc::drivers
