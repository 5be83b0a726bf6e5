#include "tools/experiment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "firmware/descriptor.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/angles.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/dsp/vanilla_descriptor.h"
#include "skyloc/sim/imu_model.h"
#include "tools/eval_score.h"
#include "tools/fabmap_eval.h"
#include "tools/features.h"

namespace skyloc::tools {

// The simulator's worlds, renderer and motion, which the experiments drive.
using drivers::DspStatus;
using firmware::Matcher;
using sim::BuildTrajectory;
using sim::DefaultSimLens;
using sim::EstimateAttitudes;
using sim::ImuModelConfig;
using sim::ImuSeedForRun;
using sim::LightingPreset;
using sim::LoadRouteCsv;
using sim::LoadSevilleWorld;
using sim::MakeProceduralWorld;
using sim::MotionConfig;
using sim::Point2;
using sim::Renderer;
using sim::Sampling;
using sim::Spectrum;
using sim::TrajectoryPoint;
using sim::World;
using sim::WorldKind;
using sim::WorldKindName;

namespace {

// The zenith the gravity-aligned cap uses at each frame of a run (body frame: the lens's).
// The simulated IMU's noise and bias are seeded from the run's own seed.
Status RunAttitudes(const std::vector<TrajectoryPoint>& trajectory, AttitudeInput input,
                    std::uint64_t seed, std::vector<dsp::Attitude>* out) {
  out->clear();
  if (input == AttitudeInput::kNone)
    return Status::Ok();
  if (input == AttitudeInput::kImage) {  // estimated frame by frame in DescribeRun
    out->assign(trajectory.size(), dsp::Attitude{});
    return Status::Ok();
  }
  if (input == AttitudeInput::kTruth) {
    for (const TrajectoryPoint& t : trajectory) {
      out->push_back(dsp::AttitudeFromRollPitch(static_cast<std::int64_t>(t.time_s * 1e9),
                                                t.pose.roll_deg, t.pose.pitch_deg));
    }
  } else {
    ImuModelConfig imu;
    imu.seed = ImuSeedForRun(seed);
    SKYLOC_TRY(EstimateAttitudes(trajectory, imu, dsp::AttitudeFilterParams{}, out));
  }
  return Status::Ok();
}

// The largest tilt (angle between body z and the world zenith) a run with these manoeuvres
// reaches: a constant pitch plus roll and pitch bumps, each up to bumps_deg.
double LargestTiltDeg(double tilt_deg, double bumps_deg) {
  const double pitch = (std::fabs(tilt_deg) + bumps_deg) * dsp::kDegToRad;
  const double roll = bumps_deg * dsp::kDegToRad;
  return std::acos(std::cos(pitch) * std::cos(roll)) / dsp::kDegToRad;
}

// The options with the cap on (when attitude is) at the elevation a user expecting tilts up
// to max_tilt_deg would configure, unless the caller set one.
// The angle between each frame's cap zenith and the true one.
ZenithError ZenithErrorOf(const std::vector<TrajectoryPoint>& trajectory,
                          const std::vector<dsp::Attitude>& attitude, int no_estimate) {
  ZenithError e;
  e.no_estimate = no_estimate;
  if (attitude.size() != trajectory.size() || attitude.empty())
    return e;
  std::vector<double> errors;
  errors.reserve(attitude.size());
  for (std::size_t i = 0; i < attitude.size(); ++i) {
    const std::array<double, 3> truth =
        dsp::UpFromRollPitch(trajectory[i].pose.roll_deg, trajectory[i].pose.pitch_deg);
    const std::array<double, 3>& u = attitude[i].up;
    const double c = std::clamp(u[0] * truth[0] + u[1] * truth[1] + u[2] * truth[2], -1.0, 1.0);
    errors.push_back(std::acos(c) * 180.0 / 3.14159265358979323846);
  }
  e.frames = static_cast<int>(errors.size());
  double sum = 0;
  for (const double x : errors)
    sum += x;
  e.mean_deg = sum / static_cast<double>(errors.size());
  std::sort(errors.begin(), errors.end());
  e.max_deg = errors.back();
  e.p95_deg = errors[std::min(errors.size() - 1,
                              static_cast<std::size_t>(0.95 * static_cast<double>(errors.size())))];
  return e;
}

// The options scored at sequence length ds (the matchers' ds).
ExperimentOptions AtSequenceLength(const ExperimentOptions& options, int ds) {
  ExperimentOptions o = options;
  o.seqslam.sequence_length = ds;
  return o;
}

ExperimentOptions WithCapFor(const ExperimentOptions& options, double max_tilt_deg) {
  ExperimentOptions o = options;
  o.cap = options.attitude != AttitudeInput::kNone;
  o.config.attitude.max_tilt_deg = max_tilt_deg;
  return o;
}

// A row's motion (its own tilt, bumps, zigzag and seed) sampled as the experiment's options
// say: sampling, spacing or speed profile, frame rate, camera height and frame limit.
MotionConfig RowMotion(const RunSpec& spec, const ExperimentOptions& options) {
  MotionConfig motion = spec.motion;
  motion.Resample(options.frames);
  motion.fps = options.fps;
  motion.height_m = options.camera_height_m;
  motion.max_frames = options.max_frames;
  return motion;
}

}  // namespace

Status DescribeRun(const World& world, std::span<const Point2> route, bool closed,
                   const RunSpec& spec, const ExperimentOptions& options, RunDescriptors* out) {
  const MotionConfig motion = RowMotion(spec, options);
  out->label = spec.label;
  SKYLOC_TRY(BuildTrajectory(route, closed, motion, &out->trajectory));
  out->closed_loop = closed && motion.max_frames == 0;
  Renderer renderer;
  SKYLOC_TRY(renderer.Init(&world, DefaultSimLens(options.width, options.height)));
  dsp::SkyDescriptor sky;
  const dsp::SkyDescriptorOptions sky_options =
      firmware::SkyDescriptorOptionsFrom(options.config, renderer.lens(), false);
  if (const dsp::DescriptorError e = sky.Init(renderer.lens(), sky_options); !e.ok())
    return Status::Error(StatusCode::kInvalidArgument, "sky descriptor: %s", e.message);
  dsp::SkyDescriptor sky_cap;
  if (options.cap) {
    dsp::SkyDescriptorOptions cap_options =
        firmware::SkyDescriptorOptionsFrom(options.config, renderer.lens(), true);
    if (options.cap_elevation_deg >= 0)
      cap_options.cap.elevation_deg = options.cap_elevation_deg;
    if (const dsp::DescriptorError e = sky_cap.Init(renderer.lens(), cap_options); !e.ok())
      return Status::Error(StatusCode::kInvalidArgument, "gravity-aligned sky descriptor: %s",
                           e.message);
    SKYLOC_TRY(RunAttitudes(out->trajectory, options.attitude, motion.seed, &out->attitude));
  } else {
    out->attitude.clear();
  }
  // The image's own zenith: from the hemisphere descriptor's samples (the same grid).
  dsp::ZenithEstimator zenith;
  const bool from_image = options.cap && options.attitude == AttitudeInput::kImage;
  if (from_image && !zenith.Init(sky.grid(), options.zenith))
    return Status::Error(StatusCode::kInvalidArgument, "zenith estimator: options out of range");
  int no_estimate = 0;
  const auto w = static_cast<std::size_t>(options.width);
  const auto h = static_cast<std::size_t>(options.height);
  std::vector<std::uint8_t> uv(w * h), visible(w * h * 3);
  const dsp::MutableImageView uv_view{uv.data(), options.width, options.height, w,
                                      dsp::PixelFormat::kGrey8};
  const dsp::MutableImageView visible_view{visible.data(), options.width, options.height, w * 3,
                                           dsp::PixelFormat::kRgb24};
  const std::size_t n = out->trajectory.size();
  const auto bands = static_cast<std::size_t>(sky.bands());
  out->sky.assign(n * bands, 0.0f);
  out->vanilla.assign(n * dsp::kVanillaDescriptorSize, 0.0f);
  out->sky_cap.assign(options.cap ? n * bands : 0, 0.0f);
  dsp::HorizonStrip horizon;
  const std::optional<dsp::HorizonStripOptions> strip_options =
      options.strips ? firmware::StripOptionsFrom(options.config) : std::nullopt;
  if (options.strips && !strip_options)
    return Status::Error(StatusCode::kInvalidArgument,
                         "horizon strips: the configuration's [heading] strip_columns is 0");
  if (strip_options) {
    if (const dsp::HorizonStripError e = horizon.Init(renderer.lens(), *strip_options);
        e != dsp::HorizonStripError::kOk)
      return drivers::DspStatus(e, "horizon strip");
  }
  const auto columns = strip_options ? static_cast<std::size_t>(strip_options->n_azimuth) : 0;
  out->strips.assign(n * columns, 0);
  std::vector<float> strip(columns);
  const Vocabulary* vocabulary = options.vanilla ? options.fabmap_vocabulary : nullptr;
  out->fabmap_words.assign(vocabulary != nullptr ? n : 0, WordList{});
  std::vector<float> sift;
  double sky_fraction = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const drivers::Pose& pose = out->trajectory[i].pose;
    SKYLOC_TRY(renderer.Render(pose, spec.lighting, Spectrum::kUv, i, uv_view));
    if (options.vanilla)
      SKYLOC_TRY(renderer.Render(pose, spec.lighting, Spectrum::kVisible, i, visible_view));
    dsp::SegmentationResult segmentation;
    if (const dsp::DescriptorError e = sky.Compute(
            uv_view, std::span<float>(out->sky).subspan(i * bands, bands), &segmentation);
        !e.ok())
      return Status::Error(StatusCode::kInternal, "sky descriptor of frame %zu: %s", i, e.message);
    sky_fraction += segmentation.sky_fraction;
    if (options.strips) {
      // The firmware's strip: from the same UV frame, rounded to bytes as the route stores it.
      if (const dsp::HorizonStripError e = horizon.Extract(uv_view, strip);
          e != dsp::HorizonStripError::kOk)
        return DspStatus(e, "horizon strip of frame %zu", i);
      if (const dsp::HorizonStripError e = dsp::StripToBytes(
              strip, std::span<std::uint8_t>(out->strips).subspan(i * columns, columns));
          e != dsp::HorizonStripError::kOk)
        return DspStatus(e, "horizon strip of frame %zu", i);
    }
    if (from_image) {
      const auto t_ns = static_cast<std::int64_t>(out->trajectory[i].time_s * 1e9);
      if (!zenith.Estimate(sky.samples(), t_ns, &out->attitude[i])) {
        out->attitude[i] = dsp::AttitudeFromRollPitch(t_ns, 0, 0);
        ++no_estimate;
      }
    }
    if (options.cap) {
      if (const dsp::DescriptorError e =
              sky_cap.Compute(uv_view, std::span<float>(out->sky_cap).subspan(i * bands, bands),
                              nullptr, &out->attitude[i]);
          !e.ok())
        return Status::Error(StatusCode::kInternal,
                             "gravity-aligned sky descriptor of frame %zu: %s", i, e.message);
    }
    if (!options.vanilla)
      continue;
    if (vocabulary != nullptr) {
      if (Status s = ImageWords(visible_view, *vocabulary, &sift, &out->fabmap_words[i]); !s.ok())
        return s.AddContext("FAB-MAP words of frame %zu", i);
    }
    if (const dsp::VanillaError e = dsp::VanillaDescriptor(
            visible_view,
            std::span<float>(out->vanilla)
                .subspan(i * dsp::kVanillaDescriptorSize, dsp::kVanillaDescriptorSize));
        e != dsp::VanillaError::kOk)
      return DspStatus(e, "vanilla descriptor of frame %zu", i);
  }
  out->mean_sky_fraction = n > 0 ? sky_fraction / static_cast<double>(n) : 0;
  out->zenith_error = ZenithErrorOf(out->trajectory, out->attitude, no_estimate);
  return Status::Ok();
}

Status ScoreCompared(const RunDescriptors& reference, const RunDescriptors& query,
                     const ExperimentOptions& options, ComparedScores* out) {
  SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSky, Matcher::kOpenSeqSlam, options,
                       &out->sky));
  SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kVanilla, Matcher::kOpenSeqSlam, options,
                       &out->vanilla));
  SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSky, Matcher::kRouteFilter, options,
                       &out->sky_filter));
  if (!options.cap)
    return Status::Ok();
  SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSkyCap, Matcher::kOpenSeqSlam, options,
                       &out->sky_cap));
  return ScoreRuns(reference, query, ScoredDescriptor::kSkyCap, Matcher::kRouteFilter, options,
                   &out->sky_cap_filter);
}

namespace {

// A run of the experiments: its label, its motion's seed and its sky at noon with its own
// clouds and noise (the lighting's seed).
RunSpec NoonRun(std::string label, std::uint64_t motion_seed, std::uint64_t lighting_seed) {
  RunSpec spec;
  spec.label = std::move(label);
  spec.motion.seed = motion_seed;
  LightingPreset("noon", lighting_seed, &spec.lighting);
  return spec;
}

// Describes one run, telling the progress callback its label first (runs take seconds).
Status DescribeReported(const World& world, std::span<const Point2> route, bool closed,
                        const RunSpec& spec, const ExperimentOptions& options, ProgressFn progress,
                        RunDescriptors* out) {
  if (progress != nullptr)
    progress(spec.label.c_str());
  return DescribeRun(world, route, closed, spec, options, out);
}

}  // namespace

Status RunTiltExperiment(const ExperimentOptions& tilt_options,
                         std::span<const int> differences_deg, std::vector<TiltRow>* rows,
                         ProgressFn progress) {
  // Runs pitch up to 30 degrees either way.
  const ExperimentOptions options = WithCapFor(tilt_options, LargestTiltDeg(30, 0));
  World world;
  SKYLOC_TRY(MakeProceduralWorld(WorldKind::kCity, options.world_seed, &world));
  // Runs by tilt; index 7 is the second alpha = 0 run.
  std::vector<RunDescriptors> runs(8);
  std::vector<bool> done(8, false);
  auto run_index = [](int alpha, bool second) { return second ? 7 : (alpha + 30) / 10; };
  auto get = [&](int alpha, bool second, RunDescriptors** run) -> Status {
    const int i = run_index(alpha, second);
    if (!done[static_cast<std::size_t>(i)]) {
      char label[64];
      std::snprintf(label, sizeof label, "city tilt %+d%s", alpha, second ? " (second run)" : "");
      // The paper's runs: the same place at about the same time of day (3 pm).
      RunSpec spec =
          NoonRun(label, static_cast<std::uint64_t>(100 + i), static_cast<std::uint64_t>(200 + i));
      spec.motion.tilt_deg = alpha;
      SKYLOC_TRY(DescribeReported(world, world.route, world.route_closed, spec, options, progress,
                                  &runs[static_cast<std::size_t>(i)]));
      done[static_cast<std::size_t>(i)] = true;
    }
    *run = &runs[static_cast<std::size_t>(i)];
    return Status::Ok();
  };
  rows->clear();
  for (const int difference : differences_deg) {
    if (difference < 0 || difference > 60 || difference % 10 != 0) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "tilt difference %d: expected 0, 10, ..., 60 degrees", difference);
    }
    // alpha1 ~ -alpha2: 0 -> (0, 0'), 10 -> (10, 0), 20 -> (10, -10), 30 -> (20, -10), ...
    const int alpha1 = (difference / 2 + 9) / 10 * 10;
    const int alpha2 = alpha1 - difference;
    RunDescriptors* reference = nullptr;
    RunDescriptors* query = nullptr;
    SKYLOC_TRY(get(alpha1, false, &reference));
    SKYLOC_TRY(get(alpha2, difference == 0, &query));
    TiltRow row;
    row.tilt_difference_deg = difference;
    row.reference_tilt_deg = alpha1;
    row.query_tilt_deg = alpha2;
    SKYLOC_TRY(ScoreCompared(*reference, *query, options, &row));
    if (options.fabmap_vocabulary != nullptr)
      SKYLOC_TRY(ScoreRuns(*reference, *query, ScoredDescriptor::kFabmap, Matcher::kOpenSeqSlam,
                           options, &row.fabmap));
    row.reference_zenith = reference->zenith_error;
    row.query_zenith = query->zenith_error;
    rows->push_back(std::move(row));
  }
  return Status::Ok();
}

namespace {

// The manoeuvre experiment's two runs in a world (also the heading experiment's), rendered
// and described: a smooth reference at noon, and a query at dawn that weaves +-20 degrees
// and bumps.
Status DescribeManoeuvreRuns(WorldKind kind, double bumps_deg, const ExperimentOptions& options,
                             ProgressFn progress, RunDescriptors* reference,
                             RunDescriptors* query) {
  World world;
  SKYLOC_TRY(MakeProceduralWorld(kind, options.world_seed, &world));
  const RunSpec reference_spec =
      NoonRun(std::string(WorldKindName(kind)) + " reference (noon, smooth)", 301, 401);
  RunSpec query_spec;
  query_spec.label = std::string(WorldKindName(kind)) + " query (dawn, zig-zag, bumps)";
  query_spec.motion.seed = 302;
  query_spec.motion.zigzag_deg = 20;
  query_spec.motion.zigzag_period_m = 12;
  query_spec.motion.bumps_deg = bumps_deg;
  LightingPreset("dawn", 402, &query_spec.lighting);
  SKYLOC_TRY(DescribeReported(world, world.route, world.route_closed, reference_spec, options,
                              progress, reference));
  return DescribeReported(world, world.route, world.route_closed, query_spec, options, progress,
                          query);
}

}  // namespace

Status RunManoeuvreExperiment(const ExperimentOptions& manoeuvre_options,
                              std::span<const int> ds_values, std::vector<ManoeuvreRow>* rows,
                              ProgressFn progress) {
  constexpr double kBumpsDeg = 15;
  const ExperimentOptions options = WithCapFor(manoeuvre_options, LargestTiltDeg(0, kBumpsDeg));
  rows->clear();
  for (WorldKind kind : {WorldKind::kForest, WorldKind::kRepetitive}) {
    RunDescriptors reference, query;
    SKYLOC_TRY(DescribeManoeuvreRuns(kind, kBumpsDeg, options, progress, &reference, &query));
    // FAB-MAP matches single images: one score for the world, shown on each ds row.
    MethodScore fabmap;
    if (options.fabmap_vocabulary != nullptr)
      SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kFabmap, Matcher::kOpenSeqSlam,
                           options, &fabmap));
    for (const int ds : ds_values) {
      ManoeuvreRow row;
      row.world = kind;
      row.sequence_length = ds;
      SKYLOC_TRY(ScoreCompared(reference, query, AtSequenceLength(options, ds), &row));
      row.fabmap = fabmap;
      row.reference_zenith = reference.zenith_error;
      row.query_zenith = query.zenith_error;
      rows->push_back(std::move(row));
    }
  }
  return Status::Ok();
}

namespace {

// Angle of the body's z axis from the world zenith, degrees (roll then pitch).
double TiltDeg(const drivers::Pose& pose) {
  return std::acos(std::clamp(
             std::cos(pose.roll_deg * dsp::kDegToRad) * std::cos(pose.pitch_deg * dsp::kDegToRad),
             -1.0, 1.0)) /
         dsp::kDegToRad;
}

}  // namespace

Status RunHeadingExperiment(const ExperimentOptions& heading_options, std::vector<HeadingRow>* rows,
                            ProgressFn progress) {
  constexpr double kBumpsDeg = 15;
  constexpr double kLevelTiltDeg = 10;
  ExperimentOptions options = heading_options;
  options.strips = true;
  options.vanilla = false;
  options.cap = false;
  const int columns = options.config.heading.strip.n_azimuth;
  const auto n = static_cast<std::size_t>(columns);
  // The firmware's defaults ([heading]), with (a) on every frame so it is measured alone
  // too; the answer is the firmware's either way.
  dsp::HeadingOptions heading;
  heading.surf_every_frame = true;
  dsp::HeadingEstimator estimator;
  if (const dsp::HeadingError e = estimator.Init(columns, heading); e != dsp::HeadingError::kOk)
    return drivers::DspStatus(e, "heading");
  std::vector<float> stored(n), test(n);
  std::vector<std::uint8_t> packed(dsp::PackedStripBytes(n));
  rows->clear();
  for (WorldKind kind : {WorldKind::kForest, WorldKind::kRepetitive}) {
    RunDescriptors reference, query;
    SKYLOC_TRY(DescribeManoeuvreRuns(kind, kBumpsDeg, options, progress, &reference, &query));
    HeadingRow row;
    row.world = kind;
    row.query_frames = static_cast<int>(query.trajectory.size());
    SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSky, Matcher::kRouteFilter, options,
                         &row.match));
    // Signed errors, degrees.
    std::vector<double> correlation, surf, answer, level, tilted, surf_where_uncertain;
    int frames = 0, level_frames = 0, uncertain_frames = 0;
    for (std::size_t q = 0; q < query.trajectory.size(); ++q) {
      if (!row.match.correct[q])
        continue;
      const auto r = static_cast<std::size_t>(row.match.matched[q]);
      const std::span<const std::uint8_t> taught =
          std::span<const std::uint8_t>(reference.strips).subspan(r * n, n);
      for (std::size_t j = 0; j < n; ++j) {
        stored[j] = taught[j];
        test[j] = query.strips[q * n + j];
      }
      if (options.stored_strip_bits == 4) {
        if (dsp::PackStrip(taught, packed) != dsp::HorizonStripError::kOk ||
            dsp::UnpackStrip(packed, stored) != dsp::HorizonStripError::kOk)
          return Status::Error(StatusCode::kInternal, "4-bit strip of reference frame %zu", r);
      }
      const drivers::Pose& query_pose = query.trajectory[q].pose;
      // The truth: how far the robot is turned from the taught frame's heading.
      const double truth =
          dsp::WrapDegrees(query_pose.yaw_deg - reference.trajectory[r].pose.yaw_deg);
      const bool is_level = TiltDeg(query_pose) <= kLevelTiltDeg;
      ++frames;
      level_frames += is_level ? 1 : 0;
      dsp::HeadingEstimate estimate;
      if (estimator.Estimate(stored, test, &estimate) != dsp::HeadingError::kOk)
        return Status::Error(StatusCode::kInternal, "heading of query frame %zu", q);
      if (estimate.has_correlation) {
        const double error = dsp::WrapDegrees(estimate.correlation_deg - truth);
        correlation.push_back(error);
        (is_level ? level : tilted).push_back(error);
        if (std::fabs(error) > kWrongHeadingDeg) {
          ++row.wrong_frames;
          row.wrong_certain_frames += estimate.uncertain ? 0 : 1;
        }
      }
      uncertain_frames += estimate.uncertain ? 1 : 0;
      if (estimate.has_surf) {
        surf.push_back(dsp::WrapDegrees(estimate.surf_deg - truth));
        if (estimate.uncertain)
          surf_where_uncertain.push_back(surf.back());
      }
      if (estimate.has_heading)
        answer.push_back(dsp::WrapDegrees(estimate.heading_deg - truth));
      row.uncertain_frames += estimate.uncertain ? 1 : 0;
      row.frames.push_back({static_cast<int>(q), static_cast<int>(r), truth, estimate});
    }
    row.correlation_errors_deg = correlation;
    row.surf_errors_deg = surf;
    row.answer_errors_deg = answer;
    row.answer = dsp::SummariseHeadingErrors(answer, frames);
    row.correlation = dsp::SummariseHeadingErrors(correlation, frames);
    row.surf = dsp::SummariseHeadingErrors(surf, frames);
    row.surf_where_uncertain = dsp::SummariseHeadingErrors(surf_where_uncertain, uncertain_frames);
    row.correlation_level = dsp::SummariseHeadingErrors(level, level_frames);
    row.correlation_tilted = dsp::SummariseHeadingErrors(tilted, frames - level_frames);
    rows->push_back(std::move(row));
  }
  return Status::Ok();
}

Status RunAntsExperiment(const ExperimentOptions& options, const std::string& seville_dir,
                         std::span<const double> camera_heights_m, std::vector<AntsRow>* rows,
                         ProgressFn progress) {
  World world;
  SKYLOC_TRY(LoadSevilleWorld((seville_dir + "/world5000_triangles.csv").c_str(), &world));
  struct Query {
    const char* name;
    bool same_ant;
  };
  static constexpr Query kQueries[] = {
      {"ant1_route2", true},  {"ant1_route3", true},  {"ant1_route4", true},
      {"ant1_route5", true},  {"ant2_route1", false}, {"ant3_route1", false},
      {"ant4_route1", false}, {"ant7_route1", false},
  };
  auto load = [&](const char* name, std::vector<Point2>* route) {
    return LoadRouteCsv((seville_dir + "/routes/" + name + ".csv").c_str(), route);
  };
  std::vector<Point2> reference_route;
  SKYLOC_TRY(load(kAntsReferenceRoute, &reference_route));
  rows->clear();
  for (const double height : camera_heights_m) {
    ExperimentOptions o = options;
    o.camera_height_m = height;
    char label[96];
    std::snprintf(label, sizeof label, "%s at %.2f m", kAntsReferenceRoute, height);
    RunDescriptors reference;
    SKYLOC_TRY(DescribeReported(world, reference_route, false, NoonRun(label, 501, 601), o,
                                progress, &reference));
    std::uint64_t k = 0;
    for (const Query& q : kQueries) {
      ++k;
      std::vector<Point2> route;
      SKYLOC_TRY(load(q.name, &route));
      std::snprintf(label, sizeof label, "%s at %.2f m", q.name, height);
      RunDescriptors query;
      SKYLOC_TRY(DescribeReported(world, route, false, NoonRun(label, 510 + k, 610 + k), o,
                                  progress, &query));
      AntsRow row;
      row.query = q.name;
      row.same_ant = q.same_ant;
      row.camera_height_m = height;
      SKYLOC_TRY(ScoreCompared(reference, query, o, &row));
      const auto with_truth =
          std::count_if(row.sky.truth.begin(), row.sky.truth.end(),
                        [](const dsp::TruthInterval& t) { return t.has_truth(); });
      row.truth_fraction = row.sky.truth.empty() ? 0
                                                 : static_cast<double>(with_truth) /
                                                       static_cast<double>(row.sky.truth.size());
      rows->push_back(std::move(row));
    }
  }
  return Status::Ok();
}

Status RunSpeedExperiment(const ExperimentOptions& speed_options, std::span<const int> ds_values,
                          std::vector<SpeedRow>* rows, ProgressFn progress) {
  constexpr double kBumpsDeg = 15;
  const ExperimentOptions options = WithCapFor(speed_options, LargestTiltDeg(0, kBumpsDeg));
  rows->clear();
  ExperimentOptions base = options;
  base.frames.sampling = Sampling::kTime;
  base.vanilla = false;  // the matchers are compared on the sky descriptor
  for (WorldKind kind : {WorldKind::kForest, WorldKind::kCity}) {
    World world;
    SKYLOC_TRY(MakeProceduralWorld(kind, options.world_seed, &world));
    // The taught run: the default profile (a stop at the start and two on the way).
    RunDescriptors reference;
    SKYLOC_TRY(DescribeReported(
        world, world.route, world.route_closed,
        NoonRun(std::string(WorldKindName(kind)) + " taught run (1x, stops)", 501, 601), base,
        progress, &reference));
    std::uint64_t seed = 510;
    for (const double bumps : {0.0, kBumpsDeg}) {
      for (const bool stops : {true, false}) {
        for (const double ratio : {0.5, 1.0, 2.0}) {
          ++seed;
          ExperimentOptions o = base;
          // A frame budget covers the taught run; a repeat stays within the stretch the
          // taught run covered (0.9: its own stops and speed targets differ).
          if (options.max_frames > 0)
            o.max_frames = static_cast<int>(0.9 * options.max_frames / ratio);
          if (!stops) {
            o.frames.speed.stops = 0;
            o.frames.speed.start_stop_s = 0;
          }
          char label[160];
          std::snprintf(label, sizeof label, "%s repeat %.1fx, %s, %s", WorldKindName(kind), ratio,
                        stops ? "stops" : "no stops", bumps > 0 ? "+-15 deg bumps" : "level");
          // Its own stops, speed targets and bumps (the motion's seed), clouds and noise.
          RunSpec query_spec = NoonRun(label, seed, 600 + seed);
          query_spec.motion.speed_ratio = ratio;
          query_spec.motion.bumps_deg = bumps;
          query_spec.motion.lateral_m = options.lateral_m;
          // With a frame budget a repeat ends where the taught run ended. The 0.9 above
          // assumes stops in both runs: a repeat without stops covers more ground in its
          // frames than the taught run did with its own, and its frames past the taught
          // route's end have no place to be recognised at (no ground truth). The route
          // filter stays on the last row there, so those frames measured the route's end,
          // not the matchers (docs/RESULTS.md, "Past the taught route's end"). The motion is
          // the same with fewer frames, so the frames kept are the same.
          if (options.max_frames > 0) {
            std::vector<sim::TrajectoryPoint> path;
            SKYLOC_TRY(
                BuildTrajectory(world.route, world.route_closed, RowMotion(query_spec, o), &path));
            const double taught_end_m = reference.trajectory.back().route_m;
            const auto past_end = std::find_if(path.begin(), path.end(), [&](const auto& point) {
              return point.route_m > taught_end_m;
            });
            if (past_end == path.begin())
              return Status::Error(StatusCode::kInternal, "%s starts past the taught run's end",
                                   label);
            if (past_end != path.end())
              o.max_frames = static_cast<int>(past_end - path.begin());
          }
          RunDescriptors query;
          SKYLOC_TRY(DescribeReported(world, world.route, world.route_closed, query_spec, o,
                                      progress, &query));
          for (const int ds : ds_values) {
            const ExperimentOptions scored = AtSequenceLength(o, ds);
            SpeedRow row;
            row.world = kind;
            row.speed_ratio = ratio;
            row.stops = stops;
            row.bumps_deg = bumps;
            row.sequence_length = ds;
            row.query_frames = static_cast<int>(query.trajectory.size());
            SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSky, Matcher::kOpenSeqSlam,
                                 scored, &row.openseqslam));
            SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSky, Matcher::kRouteFilter,
                                 scored, &row.filter));
            if (scored.cap) {
              SKYLOC_TRY(ScoreRuns(reference, query, ScoredDescriptor::kSkyCap,
                                   Matcher::kRouteFilter, scored, &row.filter_cap));
            }
            rows->push_back(std::move(row));
          }
        }
      }
    }
  }
  return Status::Ok();
}

}  // namespace skyloc::tools
