// Describing a dataset run for `skyloc eval`: every frame's sky descriptor (the firmware's,
// [descriptor] of the configuration, optionally above the gravity-aligned cap) and horizon
// strip, or its vanilla descriptor, on several threads. Offline (host tools): allocates.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "firmware/config.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/platform/status.h"
#include "tools/eval_match.h"
#include "tools/eval_score.h"

namespace skyloc::tools {

struct DescribeSettings {
  firmware::Config config = firmware::DefaultConfig();  // [descriptor], [attitude], [heading]
  // The sky's lens: `camera` (a camera file), else the dataset's camera.toml, else a guess
  // from the image's shape; `lens` and `fov_deg` override the model and field of view.
  std::string camera;
  std::optional<dsp::LensModel> lens;
  std::optional<double> fov_deg;
  // The sky above the gravity-aligned cap, each frame levelled by its recorded roll and
  // pitch; the cap from max_tilt_deg (unset: [attitude] max_tilt_deg).
  bool attitude_from_dataset = false;
  std::optional<double> max_tilt_deg;
  int jobs = 1;  // threads; the descriptors do not depend on it
  // The forms kept: floats (every matcher) and/or bytes (the batch matcher's vanilla).
  bool floats = true;
  bool bytes = false;
};

// The sky descriptor eval describes a run's frames with: the firmware's
// (firmware::SkyDescriptorOptionsFrom) from the settings' configuration, the cap on with
// attitude_from_dataset, its lower edge from max_tilt_deg when given.
dsp::SkyDescriptorOptions EvalSkyDescriptorOptions(const DescribeSettings& settings,
                                                   const dsp::Lens& lens);

// One run's descriptors and, for the sky, its horizon strips as the route stores them.
struct RunDescription {
  int dim = 0;
  int count = 0;
  std::vector<float> values;         // count x dim (settings.floats)
  std::vector<std::uint8_t> bytes;   // count x dim, dsp::QuantiseToBytes (settings.bytes)
  int strip_columns = 0;             // 0: no strips ([heading] off, or the lens misses the band)
  std::vector<std::uint8_t> strips;  // count x strip_columns

  DescriptorRows rows() const { return {dim, count, values, bytes}; }
  Strips horizon() const { return {strip_columns, strips}; }
};

// `descriptor` is kSky or kVanilla.
Result<RunDescription> DescribeDataset(ScoredDescriptor descriptor, const std::string& dir,
                                       const DescribeSettings& settings);

}  // namespace skyloc::tools
