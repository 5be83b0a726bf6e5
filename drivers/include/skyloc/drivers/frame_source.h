// What SimulatedCamera films. A FrameSource renders frame `index` into the camera's buffer
// (any of the camera's pixel formats) and, if it knows it, the pose the frame was taken
// from. SyntheticSkySource below is the one implementation; tests give it to the camera for
// the compliance suite and fault injection. The simulator's worlds do not come through
// here: sim::RenderedCamera (drivers/sim) is a Camera of its own, and the firmware's
// `camera.kind = "sim"` uses it or app's StreetCamera.
//
// Render() runs on the frame path: it must not allocate (tests check it through the
// simulated camera's compliance run).
#pragma once

#include <cstdint>
#include <optional>

#include "skyloc/drivers/camera.h"
#include "skyloc/dsp/image.h"

namespace skyloc::drivers {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // `out` has the camera's width, height, stride and format. Set `*pose` when known
  // (leave it empty otherwise).
  virtual void Render(std::uint64_t index, dsp::MutableImageView out,
                      std::optional<Pose>* pose) = 0;

 protected:
  FrameSource() = default;
  FrameSource(const FrameSource&) = default;
  FrameSource& operator=(const FrameSource&) = default;
};

// A deterministic upward fisheye view: a bright sky disc (equidistant lens, 180° field of
// view inscribed in the image) with dark "buildings" along the horizon whose heights vary
// with azimuth, rotating by `yaw_step_deg` per frame as if the robot turned on the spot
// while it drives forward `step_m` per frame (the pose it reports). Outside the lens
// circle the image is black, as on a real fisheye sensor. Pure function of the index.
class SyntheticSkySource final : public FrameSource {
 public:
  struct Config {
    double yaw_step_deg = 1.0;
    double step_m = 0.1;
    std::uint8_t sky_level = 220;
    std::uint8_t obstacle_level = 40;
  };
  SyntheticSkySource() = default;
  explicit SyntheticSkySource(const Config& config) : config_(config) {}

  void Render(std::uint64_t index, dsp::MutableImageView out, std::optional<Pose>* pose) override;

  // The grey level of pixel (x, y) in a `width` x `height` image of frame `index`:
  // the reference the tests compare rendered buffers with.
  std::uint8_t GreyAt(std::uint64_t index, int x, int y, int width, int height) const;

 private:
  double YawDeg(std::uint64_t index) const;

  Config config_;
};

}  // namespace skyloc::drivers
