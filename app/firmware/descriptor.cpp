#include "firmware/descriptor.h"

namespace skyloc::firmware {

double LensFieldOfViewDeg(const dsp::Lens& lens) {
  constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
  return 2 * lens.max_theta() * kRadToDeg;
}

dsp::SkyDescriptorOptions SkyDescriptorOptionsFrom(const Config& config, const dsp::Lens& lens,
                                                   bool with_attitude) {
  const DescriptorConfig& descriptor = config.descriptor;
  dsp::SkyDescriptorOptions options;
  options.bands = descriptor.bands;
  options.grid.rings = descriptor.rings;
  options.grid.longitudes = descriptor.longitudes;
  options.segmentation.fixed_threshold =
      config.segmentation.method == SegmentationMethod::kFixed ? config.segmentation.threshold : -1;
  options.normalisation = descriptor.normalisation;
  if (with_attitude) {
    options.cap.enabled = true;
    options.cap.elevation_deg =
        dsp::CapElevationForTilt(config.attitude.max_tilt_deg, LensFieldOfViewDeg(lens));
    options.cap.taper_deg = config.attitude.cap_taper_deg;
  }
  return options;
}

std::optional<dsp::HorizonStripOptions> StripOptionsFrom(const Config& config) {
  if (!config.heading.enabled())
    return std::nullopt;
  return config.heading.strip;
}

}  // namespace skyloc::firmware
