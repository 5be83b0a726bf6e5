// The simulator's worlds as a frame source: frame i is the renderer's view from the i-th
// pose of a trajectory, stamped with the trajectory's time (simulated, deterministic) and
// carrying the pose as the truth. The end of the trajectory is the end of the source
// (the camera's kOutOfRange, like the end of a dataset).
//
//   sim::RenderedSource source(&world, trajectory, config);
//   drivers::SimulatedCamera camera(source.camera_config(), &source, &clock);
//
// Prepare() (the camera's Open()) allocates the renderer's tables; Render() allocates
// nothing. The camera's size is the lens's; its format kGrey8 for kUv, kRgb24 for kVisible.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "skyloc/drivers/frame_source.h"
#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {

struct RenderedSourceConfig {
  dsp::LensParams lens = DefaultSimLens(320, 240);  // also fixes the image size
  Spectrum spectrum = Spectrum::kUv;
  Lighting lighting;
};

class RenderedSource final : public drivers::FrameSource {
 public:
  // `world` and `trajectory` must outlive the source.
  RenderedSource(const World* world, std::span<const TrajectoryPoint> trajectory,
                 const RenderedSourceConfig& config);

  // The simulated camera's configuration for this source: the lens's size, the
  // spectrum's format, one frame per trajectory point, the source's name.
  drivers::SimulatedCameraConfig camera_config() const;

  // The renderer (after the camera's Open()), for ground-truth sky masks of the same view.
  const Renderer& renderer() const { return renderer_; }

  const char* name() const override { return name_; }
  Status Prepare(int width, int height, dsp::PixelFormat format) override;
  std::uint64_t frame_count() const override { return trajectory_.size(); }
  std::optional<Nanoseconds> TimeOf(std::uint64_t index) const override;
  Status Render(std::uint64_t index, dsp::MutableImageView out,
                std::optional<drivers::Pose>* pose) override;

 private:
  const World* world_;
  std::span<const TrajectoryPoint> trajectory_;
  RenderedSourceConfig config_;
  char name_[48] = {};
  Renderer renderer_;
};

}  // namespace skyloc::sim
