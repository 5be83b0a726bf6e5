// The firmware configuration: config/skyloc.toml parsed into a plain struct once at
// start-up. Every key has a default (the struct's initialisers, which the file documents)
// and a range; an unknown key, a wrong type or an out-of-range value is an error naming
// the key and, where the parser knows it, file:line. Nothing here runs per frame.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/status_pattern.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/spherical_harmonics.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/motion.h"

namespace skyloc::firmware {

enum class CameraKind : std::uint8_t { kSim, kV4l2, kLibcamera, kDataset };
enum class SegmentationMethod : std::uint8_t { kOtsu, kFixed };
enum class GridPreset : std::uint8_t { kOversampled, kAuto, kPaper, kCustom };
enum class StatusOutputKind : std::uint8_t { kNone, kSim, kGpio };
enum class AttitudeKind : std::uint8_t { kNone, kIio, kDataset, kSim };

// The one spelling of a configuration enum's value: the config file's, the command line's
// (--grid, which has no "custom"; --matcher) and the reports'; "?" for a value outside the
// enum. For CameraKind, GridPreset, StatusOutputKind, AttitudeKind, Matcher and
// dsp::ReferenceStorage.
template <typename E>
const char* NameOf(E value);

// The reverse, from the same table: the value `name` spells, or false (and *value
// untouched). NamesOf lists every spelling in the table's order, comma-separated, for an
// error message ("float32, bfloat16, codes8, codes16"). For dsp::ReferenceStorage
// ([capacities] route_storage; tests/cost/stage_cost takes it on its command line).
template <typename E>
bool ValueOf(std::string_view name, E* value);
template <typename E>
std::string NamesOf();

// The world of a simulated run and how a run through it is sampled: what the
// configuration's [camera] sim_* keys own (and `skyloc simulate`'s --world, --seed and
// sampling options). The sampling: a frame every frame_spacing_m metres on average, or a
// frame every 1/fps seconds along a speed profile with stops (docs/SIMULATOR.md).
struct SimWorldConfig {
  std::string name = "city";  // city | forest | repetitive; config: street; simulate: seville
  std::uint64_t seed = 1;     // the procedural world's seed
  sim::FrameSampling frames;

  bool operator==(const SimWorldConfig&) const = default;
};

// A simulated run: the one description that the [camera] sim_* keys (its world), the SIM
// flags of teach, repeat and record (the rest), and `skyloc simulate` (all of it) fill.
// Its defaults are the configuration's; `skyloc simulate` starts from SimulateDefaults()
// (sim_run.h).
struct SimRunConfig {
  SimWorldConfig world;
  // The ride; its seed is the run's: it also seeds the clouds, the image noise and the
  // simulated IMU.
  sim::Ride ride;
  std::string lighting = "noon";  // noon, dawn, overcast

  bool operator==(const SimRunConfig&) const = default;
};

struct CameraConfig {
  CameraKind kind = CameraKind::kSim;
  std::string device = "/dev/video0";  // v4l2: path or "driver:card"; libcamera: camera id
  // The path keys: read relative to the config file's folder (TomlKeyReader::Path).
  std::string dataset;    // kind = dataset: the dataset folder
  std::string lens_file;  // camera/lens TOML; empty: 185° equidistant
  // Not a key: lens_file is a replayed dataset's own camera.toml (set by the session).
  bool lens_file_from_dataset = false;
  // kind = sim: the world and how a run through it is sampled (the sim_* keys); the
  // command line's SIM flags give the rest of the run.
  SimWorldConfig sim;
  // The keys width, height, fps: what a live camera is asked for (its driver's config holds
  // this value as it is), and the simulated camera's frame size and rate.
  drivers::CaptureFormat capture;
  int frame_timeout_ms = 1000;       // a Capture() waiting longer than this is a stall
  int reconnect_timeout_ms = 30000;  // an unplugged camera may take this long to return

  bool operator==(const CameraConfig&) const = default;
};

struct SegmentationConfig {
  SegmentationMethod method = SegmentationMethod::kOtsu;
  int threshold = 128;  // method = fixed: pixels brighter than this are sky

  bool operator==(const SegmentationConfig&) const = default;
};

struct DescriptorConfig {
  // L: amplitudes a_0..a_{L-1}. 120 on their oversampled grid localise better than 64 (the
  // repetitive road, the city) at 0.51 ms a 640x480 frame on one x86 core and 7.2-9.2 ms on
  // the Cortex-A53 model (docs/SKY_DESCRIPTOR.md, "Grid"); 64 is one setting away.
  int bands = 120;
  GridPreset grid = GridPreset::kOversampled;
  // Resolved by ResolveDescriptorGrid from dsp/sh_grid.h: oversampled =
  // OversampledShGridConfig(bands); auto = DefaultShGridConfig(bands), the minimal
  // unaliased grid; paper = PaperShGridConfig() (2000 points, 120 bands).
  int rings = 0;
  int longitudes = 0;
  // There is no distance key: streaming SeqSLAM compares descriptors by mean absolute
  // difference (L1), as OpenSeqSLAM does.
  // unit_l2 (a / |a|): a tilt the descriptor does not know changes how much sky the lens
  // sees, which scales every amplitude; dividing by the norm keeps the shape. Measured on
  // the speed experiment (docs/SKY_DESCRIPTOR.md, "Normalisation"): bumpy forest runs
  // without attitude P@R100 70-82 % -> 81-92 % at ds 10, level runs unchanged.
  dsp::AmplitudeNormalisation normalisation = dsp::AmplitudeNormalisation::kUnitL2;

  bool operator==(const DescriptorConfig&) const = default;
};

// Which matcher follows the route (docs/SEQSLAM.md).
enum class Matcher : std::uint8_t {
  kRouteFilter,  // dsp/route_filter.h: runs sampled in time, stops, speed changes
  kOpenSeqSlam,  // dsp/seqslam.h streaming engine: OpenSeqSLAM's enhancement and search
};

// NameOf(matcher): "filter" or "openseqslam", the spelling of [seqslam] matcher, `skyloc
// eval --matcher` and the experiments' files.

// The two matchers' own parameter structs. The keys: ds and rwindow set both
// (sequence_length, uniqueness_window); max_advance and keyframe_noise_factor are the
// filter's; vmin, vmax, vstep (v_min, v_max, v_step) and contrast_r (contrast_window)
// OpenSeqSLAM's. The file keeps the paper's short names.
struct SeqSlamConfig {
  Matcher matcher = Matcher::kRouteFilter;
  dsp::RouteFilterParams filter;
  dsp::SeqSlamParams openseqslam;

  int ds() const { return filter.sequence_length; }
  void set_ds(int ds) {
    filter.sequence_length = ds;
    openseqslam.sequence_length = ds;
  }
  int rwindow() const { return filter.uniqueness_window; }

  bool operator==(const SeqSlamConfig&) const = default;
};

struct CapacityConfig {
  int route_frames = 10000;  // the largest route teach records and repeat loads
  // How the matcher holds the route in memory (the route file stores 16-bit codes since
  // format 5, which float32 and codes16 hold exactly).
  dsp::ReferenceStorage route_storage = dsp::ReferenceStorage::kFloat32;

  bool operator==(const CapacityConfig&) const = default;
};

struct StatusConfig {
  StatusOutputKind kind = StatusOutputKind::kSim;
  std::string chip = "gpiochip0";
  int line_lost = 17;
  int line_searching = 27;
  int line_localised = 22;
  drivers::StatusLineMode encoding = drivers::StatusLineMode::kLinePerState;
  bool active_low = false;  // every output line: an indicator lit by driving its pin low
  // The teach button's input line; -1: no button. A button to ground with a pull-up reads
  // low when pressed, the usual wiring, hence active-low by default.
  int button_line = -1;
  bool button_active_low = true;
  // A press counts once the line has stayed active this long after its last edge.
  int button_debounce_ms = 50;

  bool operator==(const StatusConfig&) const = default;
};

struct RealtimeConfig {
  int sched_fifo_priority = 0;  // 0 = normal scheduling
  bool mlockall = false;
  int cpu_affinity = -1;  // -1 = any CPU

  bool operator==(const RealtimeConfig&) const = default;
};

struct RouteDbConfig {
  int flush_every = 50;  // frames per chunk: at most this many are lost on a crash

  bool operator==(const RouteDbConfig&) const = default;
};

// Where the robot's roll and pitch come from, for the gravity-aligned sky descriptor
// (docs/ATTITUDE.md, docs/SKY_DESCRIPTOR.md "Tilt").
struct AttitudeConfig {
  // none: the whole hemisphere, no cap (the descriptor of every earlier version);
  // iio: an IMU through the kernel's IIO subsystem; dataset: the roll_deg,pitch_deg columns
  // of the replayed dataset; sim: the simulated IMU of the simulated camera's run.
  AttitudeKind kind = AttitudeKind::kNone;
  std::string device;       // iio: /dev/iio:deviceN or the IIO device name (e.g. "bmi160")
  std::string gyro_device;  // iio: the gyroscope's device when separate (LSM6DSx); "": same
  std::string trigger;      // iio: the IIO trigger to attach ("": keep the device's)
  double rate_hz = 200;     // iio and sim: IMU samples per second
  // The IMU's axes in the camera's body frame (the lens's mount frame): body = Rz(yaw) *
  // Ry(pitch) * Rx(roll) * imu, as camera.toml's mount angles.
  double mount_roll_deg = 0;
  double mount_pitch_deg = 0;
  double mount_yaw_deg = 0;
  // The largest tilt the robot is expected to reach: the cap's lower edge is set from it
  // and the lens's field of view (dsp::CapElevationForTilt), and the route records it.
  double max_tilt_deg = 30;
  double cap_taper_deg = 10;
  // The attitude filter (dsp/attitude_filter.h).
  double filter_kp = 1.0;
  double filter_ki = 0.08;
  double accel_gate_mps2 = 0.4;
  // An attitude older than this at a frame's time is stale: the frame is described as if
  // level (one warning, counted), never dropped.
  int stale_ms = 250;
  bool operator==(const AttitudeConfig&) const = default;
};

// The heading of a recognised place (docs/SURF1D.md, "Heading in the firmware"): every
// route frame stores a horizon strip, and repeat turns the query's strip against the
// matched frame's.
// dsp's own option structs, filled from the keys: strip_columns -> strip.n_azimuth,
// band_rows, elevation_min_deg, elevation_max_deg -> strip; surf -> estimate.surf,
// surf_threshold -> estimate.features.threshold (strip grey levels), surf_max_features ->
// estimate.max_features, surf_min_inliers -> estimate.min_surf_inliers.
struct HeadingConfig {
  // strip.n_azimuth: azimuth columns over 360 degrees, 0 (no heading, no strips) or
  // 148..4096 (1D SURF's widest filter needs more than 147). The route stores one byte per
  // column per frame. estimate.surf: the second estimate, 1D SURF + RANSAC on the same
  // strips (heading_surf_deg), run only where the cross-correlation is uncertain
  // (dsp/heading.h); off never runs it.
  dsp::HorizonStripOptions strip;
  dsp::HeadingOptions estimate;
  bool enabled() const { return strip.n_azimuth > 0; }

  bool operator==(const HeadingConfig&) const = default;
};

// [output]: where each frame's localisation goes for the robot's controller, besides the
// status lines (docs/OUTPUTS.md). Any of the three; the same JSON line on stdout and the
// socket, the same values on DDS.
struct OutputConfig {
  bool to_stdout = true;   // "stdout": the JSON lines (the journal, under the systemd unit)
  bool to_socket = false;  // "socket": a local SOCK_SEQPACKET socket, one line per message
  bool to_dds = false;     // "dds": ROS 2 topics through Eclipse Cyclone DDS
  std::string socket_path = "/run/skyloc/localisation.sock";
  int socket_max_readers = 8;
  // The ROS 2 topic (DDS topic "rt" + topic) and domain (ROS_DOMAIN_ID).
  std::string ros_topic = "/skyloc/localisation";
  int ros_domain_id = 0;
  std::string frame_id = "skyloc";  // std_msgs/Header frame_id of every message

  bool operator==(const OutputConfig&) const = default;
};

struct Config {
  // The file it was read from, or what built it in memory (the demo); empty: the built-in
  // defaults.
  std::string source;
  CameraConfig camera;
  SegmentationConfig segmentation;
  DescriptorConfig descriptor;
  SeqSlamConfig seqslam;
  CapacityConfig capacities;
  // [state]: the state machine's own parameters (docs/STATE_MACHINE.md). Its velocity band
  // (vmin, vmax) is not a key: it follows the matcher (StateMachineParamsFrom).
  dsp::StateMachineParams state;
  StatusConfig status;
  RealtimeConfig realtime;
  RouteDbConfig route_db;
  AttitudeConfig attitude;
  HeadingConfig heading;
  OutputConfig output;

  bool operator==(const Config&) const = default;
};

// The defaults, with the derived fields (descriptor grid) resolved.
Config DefaultConfig();

// Sets rings and longitudes from the grid preset and the bands (custom: left as they are).
// For a tool that changes the bands of a parsed configuration (skyloc eval --bands).
void ResolveDescriptorGrid(DescriptorConfig* descriptor);

// Parses TOML text; `source_name` names it in messages (usually the path).
Result<Config> ParseConfig(std::string_view text, std::string_view source_name);
// Reads and parses a file. A missing file is kNotFound naming the path.
Result<Config> LoadConfigFile(const char* path);

// Whether a path key's ("[camera] dataset") file or folder is there and of its kind; else
// one error naming the config file, the key and its path, what is wrong (not found, not a
// folder, not a file) and the fix.
enum class PathKind : std::uint8_t { kFile, kFolder };
Status CheckPathKey(const Config& config, const char* key, const std::string& path, PathKind kind);

}  // namespace skyloc::firmware
