#include "firmware/pipeline.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "firmware/descriptor.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dsp_status.h"

namespace skyloc::firmware {

using drivers::DspStatus;

namespace {

void HashBytes(std::uint64_t* h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    *h ^= p[i];
    *h *= 0x100000001b3ull;  // FNV-1a 64
  }
}
template <typename T>
void Hash(std::uint64_t* h, const T& v) {
  HashBytes(h, &v, sizeof v);
}

}  // namespace

Result<dsp::LensParams> LensFromConfig(const Config& config) {
  const CameraConfig& cam = config.camera;
  if (!cam.lens_file.empty()) {
    if (!cam.lens_file_from_dataset)
      SKYLOC_TRY(CheckPathKey(config, "[camera] lens_file", cam.lens_file, PathKind::kFile));
    Result<dsp::LensParams> p = drivers::LoadCameraFile(cam.lens_file.c_str());
    if (!p.ok()) {
      Status s = p.status();
      if (cam.lens_file_from_dataset)
        return s.AddContext("the dataset's camera file");
      return s.AddContext("[camera] lens_file in %s",
                          config.source.empty() ? "the built-in defaults" : config.source.c_str());
    }
    if (p->width != cam.capture.width || p->height != cam.capture.height) {
      if (cam.lens_file_from_dataset) {
        return Status::Error(StatusCode::kInvalidArgument,
                             "the dataset's camera file %s is for %dx%d images but its frames "
                             "are %dx%d: correct that camera.toml, or set [camera] lens_file",
                             cam.lens_file.c_str(), p->width, p->height, cam.capture.width,
                             cam.capture.height);
      }
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s: [camera] lens_file %s is for %dx%d images but the frames are "
                           "%dx%d: make them agree",
                           config.source.empty() ? "built-in defaults" : config.source.c_str(),
                           cam.lens_file.c_str(), p->width, p->height, cam.capture.width,
                           cam.capture.height);
    }
    return p;
  }
  dsp::LensParams p;
  p.model = dsp::LensModel::kEquidistant;
  p.width = config.camera.capture.width;
  p.height = config.camera.capture.height;
  p.fov_deg = 185.0;
  return p;
}

std::uint64_t LensHash(const dsp::LensParams& p) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  Hash(&h, p.model);
  Hash(&h, p.width);
  Hash(&h, p.height);
  for (double v : {p.centre_x, p.centre_y, p.radius_px, p.fov_deg, p.fx, p.fy, p.k[0], p.k[1],
                   p.k[2], p.k[3], p.roll_deg, p.pitch_deg, p.yaw_deg})
    Hash(&h, v);
  if (p.model == dsp::LensModel::kOCamCalib) {
    HashBytes(&h, p.ocam.ss.data(), sizeof p.ocam.ss);
    HashBytes(&h, p.ocam.invpol.data(), sizeof p.ocam.invpol);
    for (double v : {p.ocam.row_centre, p.ocam.column_centre, p.ocam.c, p.ocam.d, p.ocam.e})
      Hash(&h, v);
  }
  return h;
}

RouteDbLens RouteLensFrom(const dsp::Lens& lens) {
  const dsp::LensParams& p = lens.params();
  RouteDbLens l;
  l.known = true;
  l.model = static_cast<std::uint32_t>(p.model);
  l.width = static_cast<std::uint32_t>(p.width);
  l.height = static_cast<std::uint32_t>(p.height);
  // The effective values (an unset centre or radius resolved as the lens resolved it).
  l.centre_x = lens.centre_x();
  l.centre_y = lens.centre_y();
  l.radius_px = lens.radius_px();
  l.fov_deg = p.fov_deg;
  if (p.model == dsp::LensModel::kKannalaBrandt) {
    l.fx = p.fx;
    l.fy = p.fy;
    l.k = p.k;
  }
  l.roll_deg = p.roll_deg;
  l.pitch_deg = p.pitch_deg;
  l.yaw_deg = p.yaw_deg;
  if (p.model == dsp::LensModel::kOCamCalib) {
    // Too large for the fixed record: a hash of what defines the mapping. The unused
    // polynomial terms are zero, so a file written out and read back hashes the same.
    std::uint64_t h = 0xcbf29ce484222325ull;
    Hash(&h, p.ocam.ss_count);
    Hash(&h, p.ocam.invpol_count);
    HashBytes(&h, p.ocam.ss.data(), sizeof p.ocam.ss);
    HashBytes(&h, p.ocam.invpol.data(), sizeof p.ocam.invpol);
    for (double v : {p.ocam.row_centre, p.ocam.column_centre, p.ocam.c, p.ocam.d, p.ocam.e})
      Hash(&h, v);
    l.ocam_hash = h == 0 ? 1 : h;  // 0 means "no OCamCalib hash"
  }
  return l;
}

dsp::StateMachineParams StateMachineParamsFrom(const Config& config) {
  dsp::StateMachineParams sm = config.state;
  // Route-index consistency in the matcher's rows: the filter's position stands still or
  // advances up to max_advance rows per frame; OpenSeqSLAM's moves at vmin..vmax.
  const bool filter = config.seqslam.matcher == Matcher::kRouteFilter;
  sm.vmin = filter ? 0.0 : static_cast<double>(config.seqslam.openseqslam.v_min);
  sm.vmax = filter ? config.seqslam.filter.max_advance
                   : static_cast<double>(config.seqslam.openseqslam.v_max);
  return sm;
}

std::vector<dsp::LocalisationState> ReplayStateMachine(const Config& config,
                                                       std::span<const dsp::SeqSlamMatch> matches) {
  dsp::LocalisationStateMachine machine;
  machine.Init(StateMachineParamsFrom(config));
  std::vector<dsp::LocalisationState> states;
  states.reserve(matches.size());
  for (std::size_t t = 0; t < matches.size(); ++t) {
    const dsp::SeqSlamMatch& m = matches[t];
    dsp::MatchObservation obs;
    obs.frame = t;
    obs.index = m.valid ? m.row : -1;  // rows: see StateMachineParamsFrom
    obs.uniqueness = m.valid ? m.uniqueness : 1.0f;
    obs.confidence = m.valid ? m.confidence : 0.0f;
    states.push_back(machine.Update(obs));
  }
  return states;
}

Status Pipeline::Init(const Config& config) {
  SKYLOC_TRY_ASSIGN(const dsp::LensParams lens_params, LensFromConfig(config));
  if (const dsp::LensError e = lens_.Init(lens_params); e != dsp::LensError::kOk)
    return DspStatus(e, "lens");

  const dsp::SkyDescriptorOptions options =
      SkyDescriptorOptionsFrom(config, lens_, config.attitude.kind != AttitudeKind::kNone);
  uses_attitude_ = options.cap.enabled;
  if (const dsp::DescriptorError e = descriptor_.Init(lens_, options); !e.ok())
    return Status::Error(
        StatusCode::kInvalidArgument, "%s: %s",
        options.cap.enabled ? "[attitude] max_tilt_deg/cap_taper_deg" : "[descriptor]", e.message);
  SKYLOC_TRY(amplitudes_.Allocate(static_cast<std::size_t>(descriptor_.bands())));

  matcher_ = config.seqslam.matcher;
  const dsp::ReferenceStorage storage = config.capacities.route_storage;
  dsp::SeqSlamError matcher_error = dsp::SeqSlamError::kOk;
  if (matcher_ == Matcher::kRouteFilter) {
    matcher_error = filter_.Init(config.seqslam.filter, descriptor_.bands(),
                                 config.capacities.route_frames, storage);
  } else {
    matcher_error = seqslam_.Init(config.seqslam.openseqslam, descriptor_.bands(),
                                  config.capacities.route_frames, storage);
  }
  if (matcher_error != dsp::SeqSlamError::kOk)
    return DspStatus(matcher_error, "[seqslam]");

  const dsp::StateMachineParams sm = StateMachineParamsFrom(config);
  if (const dsp::StateMachineError e = state_.Init(sm); e != dsp::StateMachineError::kOk)
    return DspStatus(e, "[state]");

  route_settings_ = {};
  route_settings_.descriptor_kind = kDescriptorSkyShAmplitudes;
  route_settings_.bands = static_cast<std::uint32_t>(descriptor_.bands());
  route_settings_.rings = static_cast<std::uint32_t>(config.descriptor.rings);
  route_settings_.longitudes = static_cast<std::uint32_t>(config.descriptor.longitudes);
  route_settings_.dim = static_cast<std::uint32_t>(descriptor_.bands());
  route_settings_.normalisation = static_cast<std::uint32_t>(config.descriptor.normalisation);
  route_settings_.lens_hash = LensHash(lens_params);
  route_settings_.lens = RouteLensFrom(lens_);
  if (options.cap.enabled) {
    route_settings_.gravity_cap_cdeg =
        static_cast<std::uint32_t>(std::lround(options.cap.elevation_deg * 100));
    route_settings_.gravity_cap_taper_cdeg =
        static_cast<std::uint32_t>(std::lround(options.cap.taper_deg * 100));
  }

  SKYLOC_TRY(InitHeading(config.heading));
  // The route's strips, once, packed: the loader hands them here (RouteSink), not kept
  // elsewhere.
  SKYLOC_TRY(route_strips_.Allocate(static_cast<std::size_t>(config.capacities.route_frames) *
                                    route_strip_bytes()));

  latency_ = LatencyTable();
  stages_.capture = latency_.AddStage("capture");
  stages_.descriptor = latency_.AddStage("descriptor");
  stages_.seqslam = latency_.AddStage("seqslam");
  stages_.heading = latency_.AddStage("heading");
  stages_.output = latency_.AddStage("output");
  stages_.total = latency_.AddStage("total");
  return Status::Ok();
}

Status Pipeline::InitHeading(const HeadingConfig& config) {
  route_settings_.strip = {};
  route_strip_frames_ = 0;
  stored_frame_ = kNoStoredFrame;
  const auto columns = static_cast<std::size_t>(config.strip.n_azimuth);
  // Zero-sized buffers when heading is off: strip() is then empty and teach stores none.
  SKYLOC_TRY(strip_.Allocate(columns));
  SKYLOC_TRY(strip_bytes_.Allocate(columns));
  SKYLOC_TRY(stored_strip_.Allocate(columns));
  if (columns == 0)
    return Status::Ok();
  const dsp::HorizonStripOptions& strip = config.strip;
  if (const dsp::HorizonStripError e = horizon_.Init(lens_, strip);
      e != dsp::HorizonStripError::kOk)
    return DspStatus(e, "[heading]");
  // The band as the route records it: hundredths of a degree, so a value written to the
  // config file and read back compares equal.
  route_settings_.strip.columns = static_cast<std::uint32_t>(strip.n_azimuth);
  route_settings_.strip.band_rows = static_cast<std::uint32_t>(strip.band_rows);
  route_settings_.strip.elevation_min_cdeg =
      static_cast<std::int32_t>(std::lround(strip.elevation_min_deg * 100));
  route_settings_.strip.elevation_max_cdeg =
      static_cast<std::int32_t>(std::lround(strip.elevation_max_deg * 100));
  if (const dsp::HeadingError e = heading_.Init(strip.n_azimuth, config.estimate);
      e != dsp::HeadingError::kOk)
    return DspStatus(e, "[heading]");
  return Status::Ok();
}

void Pipeline::BeginRoute() {
  if (matcher_ == Matcher::kRouteFilter)
    filter_.ClearReferences();
  else
    seqslam_.ClearReferences();
  route_frames_added_ = 0;
  route_strips_complete_ = true;
  route_strip_frames_ = 0;
  stored_frame_ = kNoStoredFrame;  // the route's strips change
}

Status Pipeline::AddFrame(std::span<const float> descriptor, std::span<const std::uint8_t> strip) {
  if (descriptor.size() != static_cast<std::size_t>(dim())) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "route has %zu-value descriptors, the pipeline %d", descriptor.size(),
                         dim());
  }
  if (const dsp::SeqSlamError e = matcher_ == Matcher::kRouteFilter
                                      ? filter_.AddReference(descriptor)
                                      : seqslam_.AddReference(descriptor);
      e != dsp::SeqSlamError::kOk)
    return DspStatus(e, "route frame %zu", route_frames_added_);
  // Strips of another length cannot be compared (the route loader refuses them; this
  // guards a route built in memory): a route with any frame without one has no heading.
  const std::size_t packed = route_strip_bytes();
  if (packed != 0 && strip.size() == packed &&
      (route_frames_added_ + 1) * packed <= route_strips_.size())
    std::memcpy(route_strips_.data() + route_frames_added_ * packed, strip.data(), packed);
  else
    route_strips_complete_ = false;
  ++route_frames_added_;
  return Status::Ok();
}

Status Pipeline::SetRoute(const RouteFrames& route) {
  if (route.dim() != static_cast<std::size_t>(dim())) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "route has %zu-value descriptors, the "
                         "pipeline %d",
                         route.dim(), dim());
  }
  if (route.sink() != static_cast<const RouteSink*>(this)) {
    // A route kept in memory (tests, tools): hand its frames over as the loader would.
    BeginRoute();
    for (std::size_t i = 0; i < route.size(); ++i)
      SKYLOC_TRY(AddFrame(route.descriptor(i), route.strip(i)));
  } else if (route_frames_added_ != route.size()) {
    return Status::Error(StatusCode::kInternal,
                         "route: %zu frames loaded, the matcher received %zu", route.size(),
                         route_frames_added_);
  }
  if (matcher_ == Matcher::kRouteFilter) {
    if (const dsp::SeqSlamError e = filter_.FinishRoute(); e != dsp::SeqSlamError::kOk)
      return DspStatus(e, "route");
  }
  route_strip_frames_ = route.has_strips() && route_strips_complete_ ? route_frames_added_ : 0;
  ResetTracking();
  return Status::Ok();
}

std::size_t Pipeline::route_size() const {
  return static_cast<std::size_t>(matcher_ == Matcher::kRouteFilter ? filter_.frames()
                                                                    : seqslam_.size());
}

void Pipeline::ResetTracking() {
  filter_.ResetQueries();
  seqslam_.ResetQueries();
  state_.Reset();
}

Status Pipeline::Describe(const dsp::ImageView& image, FrameResult* result,
                          const dsp::Attitude* attitude) {
  StageTimer timer(latency_, stages_.descriptor, *clock_);
  dsp::SegmentationResult segmentation;
  if (const dsp::DescriptorError e =
          descriptor_.Compute(image, amplitudes_.span(), &segmentation, attitude);
      !e.ok()) {
    return DspStatus(e, "frame %llu (%dx%d %s)", static_cast<unsigned long long>(result->frame),
                     image.width, image.height, dsp::PixelFormatName(image.format));
  }
  result->threshold = segmentation.threshold;
  result->sky_fraction = static_cast<float>(segmentation.sky_fraction);
  result->sky_contrast = segmentation.sky_contrast;
  if (!strip_.empty()) {
    // Read through the body frame as the lens sees it: a tilted robot's band moves up on
    // one side and down on the other (docs/RESULTS.md, "Heading").
    if (const dsp::HorizonStripError e = horizon_.Extract(image, strip_.span());
        e != dsp::HorizonStripError::kOk)
      return DspStatus(e, "frame %llu: horizon strip",
                       static_cast<unsigned long long>(result->frame));
    if (const dsp::HorizonStripError e = dsp::StripToBytes(strip_.span(), strip_bytes_.span());
        e != dsp::HorizonStripError::kOk)
      return DspStatus(e, "frame %llu: horizon strip bytes",
                       static_cast<unsigned long long>(result->frame));
  }
  return Status::Ok();
}

void Pipeline::EstimateHeading(std::size_t route_frame, FrameResult* result) {
  StageTimer timer(latency_, stages_.heading, *clock_);
  // Unpacked when the matched route frame changes: a localised robot holds one for many
  // frames (and the estimator keeps what it computed from the same strip).
  if (route_frame != stored_frame_) {
    const std::size_t packed = route_strip_bytes();
    if (dsp::UnpackStrip(route_strips_.span().subspan(route_frame * packed, packed),
                         stored_strip_.span()) != dsp::HorizonStripError::kOk)
      return;  // strips of the configured length by construction (SetRoute)
    stored_frame_ = route_frame;
  }
  // The query in bytes, as teach hands its strip to the route; the route keeps 4 bits a
  // column, which the heading experiment measured (docs/RESULTS.md, "Heading").
  for (std::size_t j = 0; j < strip_.size(); ++j)
    strip_[j] = strip_bytes_[j];
  dsp::HeadingEstimate estimate;
  if (heading_.Estimate(stored_strip_.span(), strip_.span(), &estimate) != dsp::HeadingError::kOk)
    return;  // strips of the configured length by construction (SetRoute)
  result->has_heading = estimate.has_heading;
  result->heading_deg = static_cast<float>(estimate.heading_deg);
  result->heading_confidence = estimate.confidence;
  result->has_heading_surf = estimate.has_surf;
  result->heading_surf_deg = static_cast<float>(estimate.surf_deg);
  result->heading_surf_inliers = estimate.surf_inliers;
}

Status Pipeline::Localise(const drivers::Frame& frame, FrameResult* result,
                          const dsp::Attitude* attitude) {
  result->frame = frame.sequence;
  result->timestamp = frame.timestamp;
  result->has_pose = frame.pose.has_value();
  if (frame.pose)
    result->pose = *frame.pose;
  SKYLOC_TRY(Describe(frame.image, result, attitude));
  dsp::SeqSlamMatch match;
  if (result->sky_contrast) {
    StageTimer timer(latency_, stages_.seqslam, *clock_);
    if (const dsp::SeqSlamError e = matcher_ == Matcher::kRouteFilter
                                        ? filter_.Step(amplitudes_.span(), &match)
                                        : seqslam_.Step(amplitudes_.span(), &match);
        e != dsp::SeqSlamError::kOk)
      return DspStatus(e, "seqslam");
  }
  result->matched = match.valid;
  result->best_index = match.valid ? match.reference : -1;
  result->score = match.score;
  result->uniqueness = match.valid ? match.uniqueness : 1.0f;
  result->confidence = match.valid ? match.confidence : 0.0f;
  dsp::MatchObservation obs;
  obs.frame = frame.sequence;
  obs.index = match.valid ? match.row : -1;  // rows: see sm.vmin/vmax in Init
  obs.uniqueness = result->uniqueness;
  obs.confidence = result->confidence;
  result->state = state_.Update(obs);
  if (match.valid && heading_enabled() && match.reference >= 0 &&
      static_cast<std::size_t>(match.reference) < route_strip_frames_)
    EstimateHeading(static_cast<std::size_t>(match.reference), result);
  return Status::Ok();
}

}  // namespace skyloc::firmware
