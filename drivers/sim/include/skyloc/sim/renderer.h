// Upward fisheye views of a World from a 6-DoF pose, in UV or visible light.
//
// Camera conventions (also in docs/SIMULATOR.md):
//   body frame  x forward, y left, z up; pose yaw about z (counter-clockwise from world +x,
//               the ant-route MATLAB convention), pitch positive = nose up, roll positive =
//               right side down; R_world_body = Rz(yaw) * Ry(-pitch) * Rx(roll).
//   camera      optical axis = body +z (the sky); image right = body left (+y), image down
//               = body backward (-x): the top of the image is the direction of travel, as
//               seen lying on one's back with the head forward.
//   lens        dsp::Lens (skyloc/dsp/lens.h, the same model and camera file as the real
//               camera): equidistant 185 degrees across the shorter side by default. The
//               lens's own "body" frame (its mount rotation applied) is taken as the
//               camera frame above, so a camera file's mount angles tilt the view too.
//               Pixels outside the image circle are black. A pinhole lens mounted with
//               roll -90, yaw -90 (camera z = body +x, image right = body -y) is a
//               forward camera (the 1D SURF experiment, app/tools/surf1d_experiment.h).
//
// Init() allocates a table of per-pixel ray directions; Render() allocates nothing and is
// deterministic: the same world, pose, lighting and frame seed give the same bytes.
#pragma once

#include <cstdint>

#include "skyloc/drivers/camera.h"
#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {

enum class Spectrum : std::uint8_t {
  kUv,       // kGrey8: bright sky, dark ground and vegetation (through the UV bandpass)
  kVisible,  // kRgb24: coloured, textured, sun-shaded scene and a blue, cloudy sky
};
const char* SpectrumName(Spectrum s);

// What changes between runs in the same place: sun, clouds, exposure, sensor noise.
struct Lighting {
  double sun_azimuth_deg = 135;   // counter-clockwise from world +x
  double sun_elevation_deg = 45;  // negative: below the horizon (no sun, no flare)
  double cloud_cover = 0.15;      // 0 clear .. 1 overcast (also hides the sun)
  double sky_brightness = 1.0;    // scales the whole sky (overcast and dawn are dimmer)
  double exposure_ev = 0.0;       // stops: image = scene * 2^ev
  double noise_sigma = 2.0;       // sensor noise, 8-bit levels (0: none)
  double flare = 1.0;             // lens flare strength when the sun is in view (0: none)
  std::uint64_t seed = 1;         // cloud pattern; noise also mixes in the frame seed
};

// "dawn", "noon", "overcast" -> a preset; false for anything else.
bool LightingPreset(const char* name, std::uint64_t seed, Lighting* lighting);

// The default lens: equidistant, 185 degrees, centred, circle filling the shorter side,
// mounted on the robot turned 90 degrees (camera x = body +y): the lens's mount angles say
// where the camera sits, so rays and the sky descriptor are in the robot's body frame.
dsp::LensParams DefaultSimLens(int width, int height);

// Rotation from body to world for a pose (row-major 3x3).
struct Rotation {
  float m[3][3];
  Vec3 Apply(Vec3 v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
};
Rotation BodyToWorld(const drivers::Pose& pose);

class Renderer {
 public:
  // `world` must outlive the renderer. Allocates the ray table.
  Status Init(const World* world, const dsp::LensParams& lens);

  // Renders one view into `out` (kGrey8 for kUv, kRgb24 for kVisible, width x height of
  // the config). `frame_seed` varies the sensor noise from frame to frame.
  Status Render(const drivers::Pose& pose, const Lighting& lighting, Spectrum spectrum,
                std::uint64_t frame_seed, const dsp::MutableImageView& out) const;

  // Ground truth: 255 where the ray reaches the sky, 0 where something blocks it (or the
  // pixel is outside the image circle). kGrey8.
  Status RenderSkyMask(const drivers::Pose& pose, const dsp::MutableImageView& out) const;

  const dsp::Lens& lens() const { return lens_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  Status CheckOutput(const dsp::MutableImageView& out, dsp::PixelFormat format) const;

  const World* world_ = nullptr;
  int width_ = 0, height_ = 0;
  dsp::Lens lens_;
  FixedArray<Vec3> rays_;            // camera-frame direction of every pixel
  FixedArray<std::uint8_t> inside_;  // 1 inside the image circle
};

}  // namespace skyloc::sim
