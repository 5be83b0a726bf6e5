// A small built-in world for the simulated camera: an upward 185-degree equidistant fisheye
// driving down a street canyon whose building heights come from a seed. `camera.kind =
// "sim"` films it for `sim_world = "street"` (the other worlds are RenderedSource's), and
// the firmware's own tests run on it: cheap enough for 100,000 frames, deterministic, with
// tilt, zig-zag yaw, lighting and speed jitter.
//
//   sim::StreetSource street(options);
//   drivers::SimulatedCamera camera(street.camera_config(), &street, &clock);
//
// or, as one object, sim::FilmedStreet below.
//
// Prepare() (the camera's Open()) allocates the per-pixel camera rays at the camera's
// size; Render() allocates nothing. Frames are grey (kGrey8) only.
#pragma once

#include <cstdint>
#include <optional>

#include "skyloc/drivers/frame_source.h"
#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/platform/fixed_array.h"

namespace skyloc::sim {

struct StreetOptions {
  int width = 640;
  int height = 480;
  std::uint64_t seed = 1;  // the street: building heights along both sides
  // Which drive along that street: the sensor noise and the speed jitter. Two runs of one
  // street differ in every frame, as two drives with a real camera do; 0 is the first.
  std::uint64_t run_seed = 0;
  double step_m = 0.5;        // metres travelled per frame
  double speed_jitter = 0.0;  // relative random variation of the step, 0..0.5
  double tilt_deg = 0.0;      // constant pitch of the camera
  double zigzag_deg = 0.0;    // yaw amplitude of a zig-zag path (period 40 frames)
  double yaw_deg = 0.0;       // constant heading offset (counter-clockwise from above)
  double brightness = 1.0;    // lighting: scales sky and ground levels
  std::uint64_t frames = 0;   // end of the run (Capture -> kOutOfRange); 0 = endless
  double fps = 30.0;          // timestamps advance by 1/fps
  bool paced = false;         // deliver frames at fps in real time, as a camera does
};

class StreetSource final : public drivers::FrameSource {
 public:
  explicit StreetSource(const StreetOptions& options);

  // The simulated camera's configuration for this street: its size, frame count, frame
  // interval, pacing and name.
  drivers::SimulatedCameraConfig camera_config() const;

  const char* name() const override { return name_; }
  Status Prepare(int width, int height, dsp::PixelFormat format) override;
  std::uint64_t frame_count() const override { return options_.frames; }
  std::optional<Nanoseconds> TimeOf(std::uint64_t index) const override;
  Status Render(std::uint64_t index, dsp::MutableImageView out,
                std::optional<drivers::Pose>* pose) override;

 private:
  void Restart();
  void Step();  // drives on to the next frame's position

  StreetOptions options_;
  char name_[48] = {};
  int width_ = 0, height_ = 0;
  FixedArray<float> rays_;  // 3 per pixel (camera frame), NaN x outside the image circle
  std::uint64_t at_ = 0;    // the frame whose position x_m_ is
  double x_m_ = 0.0;
  std::uint64_t rng_ = 0;
};

// A street and the simulated camera filming it, as one object (tests, benchmarks): use
// `.camera`; inject faults with `.camera.InjectFault()`.
struct FilmedStreet {
  explicit FilmedStreet(const StreetOptions& options)
      : source(options), camera(source.camera_config(), &source, &clock) {}
  StreetSource source;
  MonotonicClock clock;
  drivers::SimulatedCamera camera;
};

}  // namespace skyloc::sim
