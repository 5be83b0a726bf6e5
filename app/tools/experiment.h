// The paper's experiments on simulated runs: render runs through a world,
// describe every frame twice — SeqSLAM (sky): UV image -> Otsu -> SH amplitude spectrum;
// SeqSLAM (vanilla): visible image -> grey 64x32 patch-normalised — and score a reference
// run against a query run with the same SeqSLAM and precision-recall code as `skyloc eval`.
//
// Ground truth from positions by the rule of dsp/place_metrics.h (the same as `skyloc
// eval`): a query frame's truth is the interval of reference frames tied for nearest to it
// (x, y, z); a match is correct within `tolerance_frames` of that interval (the paper: 5),
// and a query frame farther than `max_offset_m` from every reference frame has no ground
// truth. Start-up/offline work: everything here allocates. Host evaluation only (it is in
// skyloc::tools, left out of the ARM firmware build); the worlds, renderer and motion
// it uses are skyloc::sim.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "firmware/config.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/dsp/zenith_estimate.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"
#include "tools/chow_liu.h"
#include "tools/eval_match.h"
#include "tools/vocabulary.h"

namespace skyloc::tools {

// Where the gravity-aligned descriptor's zenith comes from.
enum class AttitudeInput : std::uint8_t {
  kNone,          // no gravity-aligned descriptor
  kTruth,         // the true poses (an upper bound)
  kSimulatedImu,  // the simulated IMU (noise, bias) through the attitude filter: the product
  kImage,         // the image alone (dsp::ZenithEstimator on the frame's sky samples; level
                  // when it gives no estimate): experimental
};

struct ExperimentOptions {
  int width = 320;
  int height = 240;
  // The firmware configuration the sky descriptor is built from, through the firmware's own
  // factory (firmware::SkyDescriptorOptionsFrom): [descriptor] bands, grid and
  // normalisation, [segmentation] and [attitude] cap_taper_deg. The defaults are the
  // robot's descriptor (120 bands, oversampled grid, unit_l2); the published tables were
  // made with 120 bands on the "auto" grid (docs/RESULTS.md gives each table's flags).
  // [attitude] max_tilt_deg is replaced by each experiment's own largest tilt. After
  // changing the bands or the grid, firmware::ResolveDescriptorGrid.
  firmware::Config config = firmware::DefaultConfig();
  // Distance sampling: a frame every frame_spacing_m. Time sampling: a frame every 1/fps
  // seconds along `speed` (each run's seed places its stops and its
  // RunSpec::motion.speed_ratio scales its cruise speed).
  sim::FrameSampling frames;
  double fps = 10;
  double camera_height_m = 1.0;
  int max_frames = 0;  // 0: the whole route
  // Speed: every repeat wanders sideways off the taught line within +-lateral_m
  // (sim::MotionConfig::lateral_m; the taught run keeps to the route). 0: on the line.
  double lateral_m = 0;
  std::uint64_t world_seed = 1;
  dsp::SeqSlamParams seqslam;     // OpenSeqSLAM defaults: ds 10, v 0.8..1.2, R 10
  dsp::RouteFilterParams filter;  // the route filter (ds taken from seqslam.sequence_length)
  bool vanilla = true;            // also render the visible image and its descriptor
  int tolerance_frames = 5;
  double max_offset_m = 3.0;  // farther than this from the reference route: no truth
  // The gravity-aligned descriptor: every run is also described with the cap (`cap` is set
  // from `attitude` by the experiments). Its lower edge comes from the experiment's own
  // largest tilt through the firmware's rule (config.attitude.max_tilt_deg), unless
  // cap_elevation_deg >= 0 sets it.
  AttitudeInput attitude = AttitudeInput::kSimulatedImu;
  bool cap = false;
  double cap_elevation_deg = -1;
  dsp::ZenithEstimateOptions zenith;  // AttitudeInput::kImage
  // Horizon strips of every frame's UV image, rounded to bytes as the firmware's query is
  // (one byte per column), for the heading: config's [heading] strip
  // (firmware::StripOptionsFrom); false: none (every other experiment).
  bool strips = false;
  // Heading: the bits a column of the route's (stored) strip, 4 as the firmware's route
  // keeps it since route format 6 (dsp::PackStrip), or 8 (a byte, formats 4 and 5, kept
  // to measure the two against each other); the query strip stays in bytes.
  int stored_strip_bits = 4;
  // FAB-MAP 2.0 (tilt and manoeuvre): the visible image's words over this vocabulary (not
  // owned; trained on runs of another world, docs/FABMAP.md). Null: no FAB-MAP column.
  const Vocabulary* fabmap_vocabulary = nullptr;
};

// How far the cap's zenith was from the true one over a run's frames (degrees).
struct ZenithError {
  double mean_deg = 0, p95_deg = 0, max_deg = 0;
  int frames = 0;
  int no_estimate = 0;  // kImage: frames the estimator gave nothing for (the cap assumed level)
};

// One simulated run: its trajectory and the descriptors of every frame.
struct RunDescriptors {
  std::string label;
  std::vector<sim::TrajectoryPoint> trajectory;
  bool closed_loop = false;    // one full lap of a closed route (scored with wrap-around)
  std::vector<float> sky;      // frames x bands
  std::vector<float> vanilla;  // frames x dsp::kVanillaDescriptorSize
  std::vector<float> sky_cap;  // frames x bands: the gravity-aligned cap (empty: attitude off)
  std::vector<dsp::Attitude> attitude;  // per frame: the zenith the cap used
  ZenithError zenith_error;             // of `attitude` against the true poses
  double mean_sky_fraction = 0;
  std::vector<std::uint8_t> strips;    // frames x strip.n_azimuth (options.strips)
  std::vector<WordList> fabmap_words;  // per frame (options.fabmap_vocabulary)
};

struct RunSpec {
  std::string label;
  // Sampling, spacing, fps, speed profile, height and max_frames come from the options;
  // the rest (seed, manoeuvres, speed_ratio) is the run's own.
  sim::MotionConfig motion;
  sim::Lighting lighting;
};

// Renders the run (UV and visible) and describes every frame.
Status DescribeRun(const sim::World& world, std::span<const sim::Point2> route, bool closed,
                   const RunSpec& spec, const ExperimentOptions& options, RunDescriptors* out);

struct MethodScore {
  dsp::PrSummary summary;
  std::vector<dsp::PrPoint> curve;
  std::vector<int> matched;                // per query frame: matched reference (-1: none)
  std::vector<dsp::SeqSlamMatch> matches;  // per query frame, as the matcher gave them
  std::vector<dsp::TruthInterval> truth;   // per query frame
  std::vector<bool> correct;               // per query frame: matched and correct
};

// The matcher over `query` against `reference` with the chosen descriptor (kSky, kSkyCap,
// kVanilla or kFabmap; FAB-MAP localises each query frame alone, no sequence or matcher),
// then precision-recall against the position ground truth (tools/eval_score.h).
Status ScoreRuns(const RunDescriptors& reference, const RunDescriptors& query,
                 ScoredDescriptor descriptor, firmware::Matcher matcher,
                 const ExperimentOptions& options, MethodScore* out);

// What the tilt, manoeuvre and ants experiments compare on a pair of runs: sky and vanilla
// with OpenSeqSLAM (the paper's comparison), the sky descriptor with the route filter (the
// firmware's matcher), and the gravity-aligned cap with both (options.cap only).
struct ComparedScores {
  MethodScore sky, vanilla;
  MethodScore sky_filter;
  MethodScore sky_cap, sky_cap_filter;
};

Status ScoreCompared(const RunDescriptors& reference, const RunDescriptors& query,
                     const ExperimentOptions& options, ComparedScores* out);

// ---- The experiments -------------------------------------------------------------------

// Tilt (the paper's City experiment): runs at alpha = -30..30 (and a second 0), paired
// alpha1 ~ -alpha2 so the tilt differences are 0, 10, ..., 60 degrees.
// The cap's scores are there when options.attitude != kNone.
struct TiltRow : ComparedScores {
  double tilt_difference_deg = 0;
  double reference_tilt_deg = 0;
  double query_tilt_deg = 0;
  MethodScore fabmap;                          // options.fabmap_vocabulary set
  ZenithError reference_zenith, query_zenith;  // the cap's zenith against the truth
};

// Progress: called before each run is rendered (may be null).
using ProgressFn = void (*)(const char* what);

Status RunTiltExperiment(const ExperimentOptions& options, std::span<const int> differences_deg,
                         std::vector<TiltRow>* rows, ProgressFn progress = nullptr);

// Manoeuvre (BMX Track and Disposal Site): a smooth reference run at noon against a query
// run at dawn with zig-zag and bumps; scored at several sequence lengths.
struct ManoeuvreRow : ComparedScores {  // the cap's scores as TiltRow
  sim::WorldKind world = sim::WorldKind::kForest;
  int sequence_length = 10;
  // FAB-MAP 2.0 (options.fabmap_vocabulary set): single images, the same on every ds row.
  MethodScore fabmap;
  ZenithError reference_zenith, query_zenith;
};

Status RunManoeuvreExperiment(const ExperimentOptions& options, std::span<const int> ds_values,
                              std::vector<ManoeuvreRow>* rows, ProgressFn progress = nullptr);

// Heading: the manoeuvre experiment's runs (reference at noon, smooth;
// query at dawn with +-20 degree zig-zag yaw and +-15 degree bumps), matched by the route
// filter (the firmware's matcher) on the sky descriptor; on every query frame matched to
// the right place, the heading relative to the matched reference frame from the two
// frames' horizon strips, (b) circular cross-correlation (dsp::AlignStrips) and (a) 1D
// SURF + RANSAC, against the truth: the query pose's yaw minus the reference pose's.
struct HeadingRow {
  sim::WorldKind world = sim::WorldKind::kForest;
  int query_frames = 0;
  MethodScore match;  // the route filter on the sky descriptor
  // (b) alone, (a) alone (run on every frame here), and the answer the firmware reports
  // (heading_deg, dsp/heading.h: (b)'s).
  dsp::HeadingErrorSummary correlation, surf, answer;
  int uncertain_frames = 0;  // where the firmware runs (a): its share of the heading's cost
  // Frames where (b) is wrong (absolute error above kWrongHeadingDeg) and, of those, the
  // ones the rule calls certain: there the firmware would not ask (a) for a second opinion.
  int wrong_frames = 0, wrong_certain_frames = 0;
  // (a) on the uncertain frames only: its accuracy where the firmware runs it.
  dsp::HeadingErrorSummary surf_where_uncertain;
  // The same frames split by the query's tilt (angle of body z from the zenith) at or
  // below / above 10 degrees, correlation only: what the bumps do to the strip.
  dsp::HeadingErrorSummary correlation_level, correlation_tilted;
  // Signed errors (estimate - truth, degrees) of the estimated frames, for pooling worlds.
  std::vector<double> correlation_errors_deg, surf_errors_deg, answer_errors_deg;
  // What the estimator said on each correctly matched query frame, in query order: the
  // per-frame record (frames.csv) that shows two builds give the same answers.
  struct Frame {
    int query = 0;         // query frame index
    int route = 0;         // matched reference frame index
    double truth_deg = 0;  // the query's yaw minus the route frame's
    dsp::HeadingEstimate estimate;
  };
  std::vector<Frame> frames;
};

// (b)'s error above which a frame counts as wrong in HeadingRow.
inline constexpr double kWrongHeadingDeg = 10.0;

Status RunHeadingExperiment(const ExperimentOptions& options, std::vector<HeadingRow>* rows,
                            ProgressFn progress = nullptr);

// Ants (Seville habitat): one ant's route as the reference, other routes of the same ant
// and of other ants as queries, at each camera height (ant ~0.01 m, small robot ~0.1 m).
// The cap's scores only with options.cap, which `skyloc experiment ants` leaves off.
struct AntsRow : ComparedScores {
  std::string query;  // route name, e.g. "ant1_route2"
  bool same_ant = false;
  double camera_height_m = 0;
  double truth_fraction = 0;  // query frames within max_offset_m of the reference route
};

inline constexpr const char* kAntsReferenceRoute = "ant1_route1";

// Speed: runs sampled in time at a fixed frame rate. A taught run with stops
// against repeat runs at 0.5x, 1x and 2x its speed, with and without stops of their own,
// level and with +-15 degree bumps, in the forest and city worlds; sky descriptor, both
// matchers at each ds.
struct SpeedRow {
  sim::WorldKind world = sim::WorldKind::kForest;
  double speed_ratio = 1;
  bool stops = true;
  double bumps_deg = 0;
  int sequence_length = 10;
  int query_frames = 0;
  MethodScore openseqslam, filter;
  MethodScore filter_cap;  // the route filter on the gravity-aligned cap (attitude on)
};

Status RunSpeedExperiment(const ExperimentOptions& options, std::span<const int> ds_values,
                          std::vector<SpeedRow>* rows, ProgressFn progress = nullptr);

Status RunAntsExperiment(const ExperimentOptions& options, const std::string& seville_dir,
                         std::span<const double> camera_heights_m, std::vector<AntsRow>* rows,
                         ProgressFn progress = nullptr);

}  // namespace skyloc::tools
