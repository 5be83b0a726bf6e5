#include "firmware/descriptor.h"

#include "skyloc/dsp/angles.h"

namespace skyloc::firmware {

double LensFieldOfViewDeg(const dsp::Lens& lens) {
  return 2 * lens.max_theta() * dsp::kRadToDeg;
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
