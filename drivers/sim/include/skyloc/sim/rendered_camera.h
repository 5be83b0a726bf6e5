// The simulated camera: a drivers::Camera that renders the next pose of a trajectory.
// Open() allocates the renderer's tables and the one frame buffer; Capture() renders into
// that buffer (no allocation) and returns Frame{image, sequence, timestamp, pose}, where the
// timestamp is the trajectory's time (simulated, deterministic) and the pose is the truth.
// The end of the trajectory is kOutOfRange, like the end of a dataset.
#pragma once

#include <span>

#include "skyloc/drivers/camera.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {

struct RenderedCameraConfig {
  dsp::LensParams lens = DefaultSimLens(320, 240);  // also fixes the image size
  Spectrum spectrum = Spectrum::kUv;
  Lighting lighting;
};

class RenderedCamera final : public drivers::Camera {
 public:
  // `world` and `trajectory` must outlive the camera.
  RenderedCamera(const World* world, std::span<const TrajectoryPoint> trajectory,
                 const RenderedCameraConfig& config);

  // The renderer, for ground-truth sky masks of the same view.
  const Renderer& renderer() const { return renderer_; }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<drivers::Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override {}
  void DoClose() override {}

  const World* world_;
  std::span<const TrajectoryPoint> trajectory_;
  RenderedCameraConfig config_;
  Renderer renderer_;
  FixedArray<std::uint8_t> buffer_;
  std::size_t next_ = 0;
};

}  // namespace skyloc::sim
