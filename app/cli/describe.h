// What `skyloc describe` describes an image with: the firmware configuration (--config, or
// the built-in defaults) with the command line's --bands, --grid and --normalisation over
// it, through the firmware's descriptor factory (firmware/descriptor.h).
#pragma once

#include <optional>

#include "firmware/config.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/platform/status.h"

namespace skyloc::cli {

// The flags that replace the configuration's [descriptor] settings (unset: kept).
struct DescribeDescriptorFlags {
  std::optional<int> bands;
  std::optional<firmware::GridPreset> grid;
  std::optional<dsp::AmplitudeNormalisation> normalisation;
};

// `config` with the flags applied and its grid resolved for the bands.
firmware::Config DescribeConfig(firmware::Config config, const DescribeDescriptorFlags& flags);

// Builds `descriptor` for images read through `lens`: the cap (as if level) when the
// configuration's [attitude] kind is not none, as the robot's pipeline.
Status InitDescribeDescriptor(const firmware::Config& config, const dsp::Lens& lens,
                              dsp::SkyDescriptor* descriptor);

}  // namespace skyloc::cli
