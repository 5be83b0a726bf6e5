// What SimulatedCamera films: every simulated camera is a SimulatedCamera (one set of
// state checks, counters, timestamps and injected faults) over a FrameSource. A source
// renders frame `index` into the camera's buffer and, if it knows it, the pose the frame
// was taken from. The sources:
//
//   SyntheticSkySource (below)   a rotating sky disc: tests, the compliance suite
//   sim::StreetSource            a street canyon from a seed: `camera.kind = "sim"` with
//                                sim_world = "street", the firmware's own tests
//   sim::RenderedSource          the simulator's worlds (city, forest, ...): `skyloc
//                                simulate`, the demo, the other sim_world values
//
// Prepare() runs in the camera's Open() and may allocate; Render() runs on the frame path
// and must not (the compliance suite checks it, for every source).
#pragma once

#include <cstdint>
#include <optional>

#include "skyloc/drivers/camera.h"
#include "skyloc/dsp/image.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // The camera name this source suggests ("sim:street(seed 7)"), used when the camera's
  // configuration names none.
  virtual const char* name() const { return "sim"; }
  // Called by the camera's Open() with its frame size and format: allocate what Render()
  // needs here. kInvalidArgument when the source cannot render that size or format.
  virtual Status Prepare(int /*width*/, int /*height*/, dsp::PixelFormat /*format*/) {
    return Status::Ok();
  }
  // How many frames the source has (the camera returns kOutOfRange after them); 0: endless.
  virtual std::uint64_t frame_count() const { return 0; }
  // When frame `index` was taken, counted from the start of the run, if the source
  // defines it (a trajectory's time); nullopt: the camera stamps frames from its clock.
  virtual std::optional<Nanoseconds> TimeOf(std::uint64_t /*index*/) const { return std::nullopt; }
  // `out` has the camera's width, height, stride and format. Set `*pose` when known
  // (leave it empty otherwise). Indices increase from one call to the next, with gaps
  // where the camera dropped frames; they start again at 0 after the camera's Open().
  virtual Status Render(std::uint64_t index, dsp::MutableImageView out,
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

  const char* name() const override { return "sim:synthetic"; }
  Status Render(std::uint64_t index, dsp::MutableImageView out, std::optional<Pose>* pose) override;

  // The grey level of pixel (x, y) in a `width` x `height` image of frame `index`:
  // the reference the tests compare rendered buffers with.
  std::uint8_t GreyAt(std::uint64_t index, int x, int y, int width, int height) const;

 private:
  double YawDeg(std::uint64_t index) const;

  Config config_;
};

}  // namespace skyloc::drivers
