// A small built-in simulated camera: an upward 185-degree equidistant fisheye driving down
// a street canyon whose building heights come from a seed. `camera.kind = "sim"` uses it
// for `sim_world = "street"` (the other worlds are the simulator's, rendered by
// sim::RenderedCamera), and the firmware's own tests run on it: cheap enough for 100,000
// frames, deterministic, with tilt, zig-zag yaw, lighting and speed jitter.
//
// Rendering allocates nothing: the per-pixel camera rays and the image are allocated in
// Open() at the configured size.
#pragma once

#include <cstdint>

#include "skyloc/drivers/camera.h"
#include "skyloc/platform/fixed_array.h"

namespace skyloc::app {

struct StreetCameraOptions {
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

class StreetCamera final : public drivers::Camera {
 public:
  explicit StreetCamera(const StreetCameraOptions& options) : options_(options) {}

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<drivers::Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override {}
  void DoClose() override {}

  void Render(double x_m, double yaw_rad, double pitch_rad);

  StreetCameraOptions options_;
  FixedArray<float> rays_;  // 3 per pixel (camera frame), NaN x outside the image circle
  FixedArray<std::uint8_t> pixels_;
  std::uint64_t next_ = 0;
  double x_m_ = 0.0;
  std::uint64_t rng_ = 0;
  MonotonicClock clock_;
  Nanoseconds start_{0};
};

}  // namespace skyloc::app
