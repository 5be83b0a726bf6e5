// The per-frame pipeline of the firmware, built once from the configuration:
//   frame -> sky descriptor (segment, sample, SH, amplitudes) -> route filter (or
//   OpenSeqSLAM's streaming engine) -> LOST/SEARCHING/LOCALISED.
// Init() is the start-up: the lens, the sampling table, the SH tables, the SeqSLAM route
// database at [capacities] route_frames, the ring of the last ds columns. After it,
// Describe() and Localise() allocate nothing (tests/app/frame_loop_test.cpp proves it).
// Time is an input: the Clock the pipeline is built with times its stages, and the frame
// loop reads the same one (clock()), so one run never mixes two clocks.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "firmware/config.h"
#include "firmware/route_db.h"
#include "skyloc/drivers/camera.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/latency.h"

namespace skyloc::firmware {

// What one frame produced. Teach fills the descriptor part only.
struct FrameResult {
  std::uint64_t frame = 0;  // the camera's sequence number
  Nanoseconds timestamp{0};
  int threshold = 0;  // the segmentation threshold
  float sky_fraction = 0;
  // The frame split into sky and ground (dsp::SegmentationResult::sky_contrast). A frame
  // without (lens cap, saturated sensor, fog) shows no place: repeat does not match it,
  // and it counts as a frame without a match, so it cannot raise the state.
  bool sky_contrast = true;
  bool matched = false;  // SeqSLAM had ds frames and a trajectory fitted the route
  std::int64_t best_index = -1;
  float score = 0;
  float uniqueness = 1;
  float confidence = 0;
  dsp::LocalisationState state = dsp::LocalisationState::kLost;
  Nanoseconds latency{0};  // from the frame leaving Capture() to the state being shown
  bool has_pose = false;   // the camera knew where it was (simulator, recorded dataset)
  drivers::Pose pose;
  // Heading relative to the matched route frame (repeat, when matched and the route has
  // horizon strips), dsp/heading.h's convention: the robot's yaw now minus its yaw when
  // the frame was taught, degrees in [-180, 180), counter-clockwise seen from above
  // positive. heading_deg is the strip cross-correlation's, heading_confidence its peak
  // (0..1); heading_surf_deg is 1D SURF + RANSAC's, with its inlier count, on the frames
  // where it ran: those whose correlation peak does not stand out of chance (dsp/heading.h).
  bool has_heading = false;
  float heading_deg = 0;
  float heading_confidence = 0;
  bool has_heading_surf = false;
  float heading_surf_deg = 0;
  int heading_surf_inliers = 0;
};

// The descriptor kinds a route database records (RouteDbSettings::descriptor_kind).
inline constexpr std::uint32_t kDescriptorSkyShAmplitudes = 1;

// The lens the configuration describes: the lens file's, or a 185-degree equidistant
// fisheye filling the image circle of a camera.capture.width x camera.capture.height frame.
Result<dsp::LensParams> LensFromConfig(const Config& config);
// A hash of everything in the lens parameters that changes which pixel a sample reads, as
// configured (unset values stay NaN). Only version-1/2 route files are checked with it.
std::uint64_t LensHash(const dsp::LensParams& lens);
// The lens as a route database stores it (format version 3): the effective centre and
// radius, the model's coefficients; OCamCalib's polynomials as a hash.
RouteDbLens RouteLensFrom(const dsp::Lens& lens);

// The state machine's parameters from [state] and the matcher's motion limits.
dsp::StateMachineParams StateMachineParamsFrom(const Config& config);
// The horizon strip and the heading estimator from [heading] (strip_columns > 0).
// The route filter's parameters from [seqslam].
// The firmware's state machine replayed over per-frame matches, as repeat would have shown
// them (offline: eval and the experiments). Allocates the result.
std::vector<dsp::LocalisationState> ReplayStateMachine(const Config& config,
                                                       std::span<const dsp::SeqSlamMatch> matches);

class Pipeline final : private RouteSink {
 public:
  // `clock` times the stages (LatencyTable) and, through clock(), the frame loop: the
  // firmware passes a MonotonicClock, tests a ManualClock so latencies and time-outs are
  // exact. It must outlive the pipeline.
  explicit Pipeline(const Clock& clock) : clock_(&clock) {}
  const Clock& clock() const { return *clock_; }

  // The latency table's stage ids, in the order it prints them: set by Init, read by the
  // frame loop, which times the stages the pipeline does not see (capture, output, total).
  struct LatencyStages {
    int capture = -1, descriptor = -1, seqslam = -1, heading = -1, output = -1, total = -1;
  };
  const LatencyStages& stages() const { return stages_; }

  Status Init(const Config& config);

  const RouteDbSettings& route_settings() const { return route_settings_; }
  int dim() const { return descriptor_.bands(); }
  int width() const { return lens_.params().width; }
  int height() const { return lens_.params().height; }

  // Where a route loader hands the frames (RouteFrames::Allocate's sink): each descriptor
  // goes straight into the matcher at its configured storage type and each strip to the
  // heading, so the route is held once (RouteFrames keeps only times and poses).
  RouteSink* route_sink() { return this; }
  // Makes the route SeqSLAM matches against (start-up, after loading the database). A
  // route loaded through route_sink() is already here: this finishes it (keyframes). Any
  // other route's descriptors and, when it has them, horizon strips are copied (the
  // route need not outlive the call).
  Status SetRoute(const RouteFrames& route);
  // Heading is estimated: [heading] strip_columns > 0 and the route has strips.
  bool heading_enabled() const { return route_strip_frames_ > 0; }
  std::size_t route_size() const;  // taught frames

  // The descriptor of one frame into descriptor(). Allocates nothing. attitude: the body's
  // zenith at the frame's time for the gravity-aligned cap ([attitude] kind != none); null
  // describes the frame as if level. Ignored without an attitude source.
  Status Describe(const dsp::ImageView& image, FrameResult* result,
                  const dsp::Attitude* attitude = nullptr);
  bool uses_attitude() const { return uses_attitude_; }
  const dsp::Lens& lens() const { return lens_; }  // the lens the frames are read through
  std::span<const float> descriptor() const { return amplitudes_.span(); }
  // The last described frame's horizon strip in bytes, a byte a column (what teach hands
  // the route, which packs it: RouteFrames, RouteDbWriter); empty when [heading]
  // strip_columns = 0.
  std::span<const std::uint8_t> strip() const { return strip_bytes_.span(); }
  // What the route database records about the strip (columns 0: none).
  const RouteDbStrip& strip_settings() const { return route_settings_.strip; }

  // Describe + SeqSLAM step + state machine. Allocates nothing. A frame without sky
  // contrast skips the matcher (as a dropped frame would) and is shown to the state
  // machine as unmatched.
  Status Localise(const drivers::Frame& frame, FrameResult* result,
                  const dsp::Attitude* attitude = nullptr);
  // Forgets the query history (a gap in the frames) and the localisation state.
  void ResetTracking();

  LatencyTable& latency() { return latency_; }
  const LatencyTable& latency() const { return latency_; }

 private:
  LatencyStages stages_;
  dsp::Lens lens_;
  dsp::SkyDescriptor descriptor_;
  Matcher matcher_ = Matcher::kRouteFilter;
  dsp::RouteFilter filter_;        // [seqslam] matcher = "filter"
  dsp::StreamingSeqSlam seqslam_;  // [seqslam] matcher = "openseqslam"; Init allocates one
  dsp::LocalisationStateMachine state_;
  FixedArray<float> amplitudes_;
  // Heading ([heading]); all sized by Init.
  Status InitHeading(const HeadingConfig& config);
  void EstimateHeading(std::size_t route_frame, FrameResult* result);
  // A route frame's packed strip (0 with heading off).
  std::size_t route_strip_bytes() const {
    return strip_.empty() ? 0 : dsp::PackedStripBytes(strip_.size());
  }
  dsp::HorizonStrip horizon_;
  FixedArray<float> strip_;               // the frame's strip, grey levels
  FixedArray<std::uint8_t> strip_bytes_;  // the same rounded to bytes, as the query compares it
  FixedArray<float> stored_strip_;        // the matched route frame's strip, unpacked
  std::size_t stored_frame_ = kNoStoredFrame;  // the route frame stored_strip_ holds
  static constexpr std::size_t kNoStoredFrame = static_cast<std::size_t>(-1);
  dsp::HeadingEstimator heading_;
  // RouteSink: the loader's frames.
  void BeginRoute() override;
  Status AddFrame(std::span<const float> descriptor, std::span<const std::uint8_t> strip) override;
  // capacity x dsp::PackedStripBytes(strip columns) (Init), filled by AddFrame: the route's
  // strips as the route keeps them, 4 bits a column.
  FixedArray<std::uint8_t> route_strips_;
  std::size_t route_frames_added_ = 0;
  bool route_strips_complete_ = true;   // every frame added had a strip of our length
  std::size_t route_strip_frames_ = 0;  // frames with strips after SetRoute (0: no heading)
  RouteDbSettings route_settings_;
  LatencyTable latency_;
  const Clock* clock_;
  std::uint64_t matched_frames_ = 0;
  bool uses_attitude_ = false;
};

}  // namespace skyloc::firmware
