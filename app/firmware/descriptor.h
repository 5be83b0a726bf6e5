// The one place a configuration becomes the sky descriptor and the horizon strip: the
// firmware's pipeline, `skyloc eval`, `skyloc describe` and the experiments all build their
// descriptors here, so a frame described by any of them gives the same bits
// (tests/tools/same_descriptor_test.cpp).
#pragma once

#include <optional>

#include "firmware/config.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::firmware {

// The full field of view of the lens the frames are read through (degrees), whatever its
// model: twice the largest angle from the optical axis it sees.
double LensFieldOfViewDeg(const dsp::Lens& lens);

// Everything that defines the sky descriptor: [descriptor] bands, rings and longitudes (as
// ResolveDescriptorGrid left them: a tool that changes the bands or the grid resolves
// again) and normalisation,
// [segmentation]'s fixed threshold (method = fixed; Otsu otherwise) and, with_attitude, the
// gravity-aligned cap: its lower edge from [attitude] max_tilt_deg and the lens's field of
// view (dsp::CapElevationForTilt), its taper [attitude] cap_taper_deg.
dsp::SkyDescriptorOptions SkyDescriptorOptionsFrom(const Config& config, const dsp::Lens& lens,
                                                   bool with_attitude);

// The horizon strip ([heading]); nullopt when strip_columns = 0 (no heading, no strips).
std::optional<dsp::HorizonStripOptions> StripOptionsFrom(const Config& config);

}  // namespace skyloc::firmware
