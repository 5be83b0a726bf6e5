#include "skyloc/dsp/image.h"

namespace skyloc::dsp {

const char* PixelFormatName(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey8:
      return "GREY";
    case PixelFormat::kRgb24:
      return "RGB24";
    case PixelFormat::kBgr24:
      return "BGR24";
    case PixelFormat::kYuyv:
      return "YUYV";
  }
  return "unknown";
}

}  // namespace skyloc::dsp
