// The sky descriptor `skyloc eval` describes a dataset's frames with: the firmware's
// (firmware::SkyDescriptorOptionsFrom) from --config with --bands applied, the cap on with
// --attitude dataset, its lower edge from --max-tilt when given.
#pragma once

#include <optional>

#include "firmware/config.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::cli {

dsp::SkyDescriptorOptions EvalSkyDescriptorOptions(firmware::Config config, const dsp::Lens& lens,
                                                   bool attitude_from_dataset,
                                                   std::optional<double> max_tilt_deg);

}  // namespace skyloc::cli
