// libFuzzer target: the camera-file parser (the camera.toml of every replayed dataset). Any
// input either fails with a message naming the file or yields lens parameters that passed
// dsp::Lens::Init and lie inside the ranges docs/CAMERA_FILE.md documents.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/toml_text.h"

namespace {

void Require(bool condition) {
  if (!condition)
    std::abort();  // an accepted camera file broke a documented range, or a message is bad
}

// lens.ocamcalib_file makes the parser open a file by a name the input chooses, and a
// name such as /dev/zero or /dev/stdin would hang the run; reading that file is
// LoadOCamCalibFile's job, which its unit tests cover. Asked through the same TOML reader,
// so a quoted or escaped spelling of the key is caught too.
bool NamesAnOCamCalibFile(std::string_view text) {
  skyloc::Result<toml::table> root = skyloc::drivers::ParseTomlText(text, "fuzz.toml");
  if (!root.ok())
    return false;
  const toml::table* lens = root->get_as<toml::table>("lens");
  return lens != nullptr && lens->contains("ocamcalib_file");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (NamesAnOCamCalibFile(text))
    return 0;
  skyloc::Result<skyloc::dsp::LensParams> p =
      skyloc::drivers::ParseCameraFile(text, "fuzz.toml", "/nonexistent");
  if (!p.ok()) {
    Require(std::string_view(p.status().message()).starts_with("fuzz.toml"));
    return 0;
  }
  Require(p->width >= 1 && p->width <= 65534);
  Require(p->height >= 1 && p->height <= 65534);
  Require(p->fov_deg > 0.0 && p->fov_deg <= 360.0);
  Require(std::fabs(p->roll_deg) <= 360.0 && std::fabs(p->pitch_deg) <= 360.0 &&
          std::fabs(p->yaw_deg) <= 360.0);
  return 0;
}
