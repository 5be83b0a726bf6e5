// `skyloc simulate`: renders a run through a simulated world and writes it as a dataset
// folder (docs/DATASETS.md) with ground-truth poses, for eval, replay, the experiments
// and the demo. docs/SIMULATOR.md describes the worlds, renderer and options.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/rendered_source.h"
#include "skyloc/sim/world.h"
#include "tools/output_file.h"

namespace skyloc::cli {
using namespace skyloc::tools;
namespace {

constexpr const char* kUsage =
    "usage: skyloc simulate --world seville|city|forest|repetitive --out DIR [options]\n"
    "\n"
    "Renders a run of an upward fisheye camera through a simulated world and writes a\n"
    "dataset folder: DIR/frames/NNNNNN.png, DIR/frames.csv (with poses), DIR/camera.toml\n"
    "(the lens, docs/CAMERA_FILE.md) and DIR/simulation.toml (how the run was made).\n"
    "With --mode both: DIR/uv/ and DIR/visible/, the same poses in both.\n"
    "\n"
    "world and route:\n"
    "  --world NAME         seville (needs the shared data folder) or a procedural world\n"
    "  --seed N             procedural world seed (default 1)\n"
    "  --route FILE         route CSV (x_cm,y_cm,... or x_m,y_m,...); default: the world's own\n"
    "                       route, for seville routes/ant1_route1.csv\n"
    "  --data DIR           Seville data folder (default ../shared/data/seville2009)\n"
    "run:\n"
    "  --run N              run seed: speed profile and stops (or speed jitter), bumps,\n"
    "                       clouds, sensor noise (default 1)\n"
    "sampling (default: in time, a frame every 1/fps s along a speed profile):\n"
    "  --fps N              camera frame rate (default 10)\n"
    "  --speed M/S          mean cruise speed (default 1; seville 0.5)\n"
    "  --speed-band F       cruise speed varies within (1 +- F) (default 0.3)\n"
    "  --accel A            acceleration and braking, m/s^2 (default 0.5)\n"
    "  --start-stop S       seconds standing before the start (default 2)\n"
    "  --stops N            stops along the route (default 2)\n"
    "  --stop-seconds MIN,MAX  each stop's length, seconds (default 2,6)\n"
    "  --spacing M          distance sampling instead: a frame every M metres on average\n"
    "                       (seville: 0.05); not with the flags above\n"
    "  --jitter F           with --spacing: speed varies within (1 +- F) (default 0.2)\n"
    "motion:\n"
    "  --camera-height M    camera above the ground (default 1, seville 0.01: an ant)\n"
    "  --start M            start this far along the route (default 0)\n"
    "  --frames N           at most N frames (default: the whole route)\n"
    "  --tilt DEG           constant pitch, nose up positive (the paper's alpha)\n"
    "  --zigzag DEG         yaw weave amplitude (period --zigzag-period M, default 20)\n"
    "  --bumps DEG          bounded random walk of roll and pitch, up to +-DEG (<= 45)\n"
    "  --yaw DEG            constant heading offset of the camera\n"
    "  --lateral M          wander sideways off the route's line within +-M metres (a drift\n"
    "                       over 40-80 m and a weave over 12-25 m), as a second drive of the\n"
    "                       same track never retraces the first (default 0, at most 5)\n"
    "appearance and camera:\n"
    "  --lighting NAME      dawn, noon (default) or overcast\n"
    "  --sun AZ,EL          sun azimuth (counter-clockwise from east) and elevation, degrees\n"
    "  --clouds F           cloud cover 0 (clear) .. 1 (overcast)\n"
    "  --exposure EV        exposure offset in stops, added to the preset's\n"
    "  --no-flare           no lens flare\n"
    "  --width W --height H image size (default 320x240) of the default lens: equidistant,\n"
    "                       185 degrees, image circle filling the shorter side\n"
    "  --camera FILE        a camera file (docs/CAMERA_FILE.md) instead: size, lens, mount\n"
    "  --mode M             uv (default), visible or both\n";

struct Options {
  sim::WorldKind world = sim::WorldKind::kCity;
  bool have_world = false;
  std::uint64_t seed = 1;
  std::uint64_t run = 1;
  std::string route_file;
  std::string data_dir = "../shared/data/seville2009";
  std::optional<double> spacing, jitter, camera_height;
  // Time sampling; unset values take sim::SpeedProfile's defaults.
  std::optional<double> fps, speed, speed_band, accel, start_stop, stop_min, stop_max;
  std::optional<int> stops;
  const char* time_flag = nullptr;  // the first time-sampling flag given (for errors)
  double start = 0, tilt = 0, zigzag = 0, zigzag_period = 20, bumps = 0, yaw = 0, lateral = 0;
  double exposure = 0;
  std::optional<double> sun_azimuth, sun_elevation, clouds;
  int frames = 0;
  std::string lighting = "noon";
  bool flare = true;
  int width = 320, height = 240;
  bool size_given = false;
  std::string camera_file;
  std::string mode = "uv";
  std::string out;
};

bool ParseDouble(const char* text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(*value);
}

bool ParseInt(const char* text, long long lo, long long hi, long long* value) {
  char* end = nullptr;
  *value = std::strtoll(text, &end, 10);
  return end != text && *end == '\0' && *value >= lo && *value <= hi;
}

// Returns kExitOk, or kExitUsage after printing one error.
int ParseArgs(std::span<char* const> args, Options* o) {
  auto fail = [](const char* flag, const char* value, const char* expected) {
    std::fprintf(stderr, "skyloc simulate: %s '%s': expected %s\n", flag, value, expected);
    return kExitUsage;
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    const char* flag = args[i];
    if (std::strcmp(flag, "--no-flare") == 0) {
      o->flare = false;
      continue;
    }
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "skyloc simulate: %s needs a value (see --help)\n", flag);
      return kExitUsage;
    }
    const char* v = args[++i];
    double d = 0;
    long long n = 0;
    if (std::strcmp(flag, "--world") == 0) {
      if (!sim::ParseWorldKind(v, &o->world))
        return fail(flag, v, "seville, city, forest or repetitive");
      o->have_world = true;
    } else if (std::strcmp(flag, "--seed") == 0) {
      if (!ParseInt(v, 0, INT64_MAX, &n))
        return fail(flag, v, "a non-negative integer");
      o->seed = static_cast<std::uint64_t>(n);
    } else if (std::strcmp(flag, "--run") == 0) {
      if (!ParseInt(v, 0, INT64_MAX, &n))
        return fail(flag, v, "a non-negative integer");
      o->run = static_cast<std::uint64_t>(n);
    } else if (std::strcmp(flag, "--route") == 0) {
      o->route_file = v;
    } else if (std::strcmp(flag, "--data") == 0) {
      o->data_dir = v;
    } else if (std::strcmp(flag, "--spacing") == 0) {
      if (!ParseDouble(v, &d) || d <= 0)
        return fail(flag, v, "a positive distance in metres");
      o->spacing = d;
    } else if (std::strcmp(flag, "--jitter") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d >= 1)
        return fail(flag, v, "a fraction in [0, 1)");
      o->jitter = d;
    } else if (std::strcmp(flag, "--fps") == 0) {
      if (!ParseDouble(v, &d) || !(d > 0 && d <= 1000))
        return fail(flag, v, "frames per second within (0, 1000]");
      o->fps = d;
      o->time_flag = o->time_flag ? o->time_flag : "--fps";
    } else if (std::strcmp(flag, "--speed") == 0) {
      if (!ParseDouble(v, &d) || !(d > 0 && d <= 100))
        return fail(flag, v, "a cruise speed within (0, 100] m/s");
      o->speed = d;
      o->time_flag = o->time_flag ? o->time_flag : "--speed";
    } else if (std::strcmp(flag, "--speed-band") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d >= 1)
        return fail(flag, v, "a fraction in [0, 1)");
      o->speed_band = d;
      o->time_flag = o->time_flag ? o->time_flag : "--speed-band";
    } else if (std::strcmp(flag, "--accel") == 0) {
      if (!ParseDouble(v, &d) || !(d > 0 && d <= 100))
        return fail(flag, v, "an acceleration within (0, 100] m/s^2");
      o->accel = d;
      o->time_flag = o->time_flag ? o->time_flag : "--accel";
    } else if (std::strcmp(flag, "--start-stop") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d > 3600)
        return fail(flag, v, "seconds within 0..3600");
      o->start_stop = d;
      o->time_flag = o->time_flag ? o->time_flag : "--start-stop";
    } else if (std::strcmp(flag, "--stops") == 0) {
      if (!ParseInt(v, 0, 1000, &n))
        return fail(flag, v, "a number of stops within 0..1000");
      o->stops = static_cast<int>(n);
      o->time_flag = o->time_flag ? o->time_flag : "--stops";
    } else if (std::strcmp(flag, "--stop-seconds") == 0) {
      char* end = nullptr;
      const double lo = std::strtod(v, &end);
      if (end == v || *end != ',')
        return fail(flag, v, "MIN,MAX seconds, e.g. 2,6");
      const char* hi_text = end + 1;
      const double hi = std::strtod(hi_text, &end);
      if (end == hi_text || *end != '\0' || !(lo >= 0 && lo <= hi && hi <= 3600))
        return fail(flag, v, "MIN,MAX seconds with 0 <= MIN <= MAX <= 3600");
      o->stop_min = lo;
      o->stop_max = hi;
      o->time_flag = o->time_flag ? o->time_flag : "--stop-seconds";
    } else if (std::strcmp(flag, "--camera-height") == 0) {
      if (!ParseDouble(v, &d) || d <= 0)
        return fail(flag, v, "a positive height in metres");
      o->camera_height = d;
    } else if (std::strcmp(flag, "--start") == 0) {
      if (!ParseDouble(v, &d) || d < 0)
        return fail(flag, v, "a non-negative distance in metres");
      o->start = d;
    } else if (std::strcmp(flag, "--frames") == 0) {
      if (!ParseInt(v, 1, 10'000'000, &n))
        return fail(flag, v, "a positive number of frames");
      o->frames = static_cast<int>(n);
    } else if (std::strcmp(flag, "--tilt") == 0) {
      if (!ParseDouble(v, &d) || std::fabs(d) > 90)
        return fail(flag, v, "degrees within -90..90");
      o->tilt = d;
    } else if (std::strcmp(flag, "--zigzag") == 0) {
      if (!ParseDouble(v, &d) || std::fabs(d) > 180)
        return fail(flag, v, "degrees within -180..180");
      o->zigzag = d;
    } else if (std::strcmp(flag, "--zigzag-period") == 0) {
      if (!ParseDouble(v, &d) || d <= 0)
        return fail(flag, v, "a positive distance in metres");
      o->zigzag_period = d;
    } else if (std::strcmp(flag, "--bumps") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d > 45)
        return fail(flag, v, "degrees within 0..45");
      o->bumps = d;
    } else if (std::strcmp(flag, "--yaw") == 0) {
      if (!ParseDouble(v, &d))
        return fail(flag, v, "degrees");
      o->yaw = d;
    } else if (std::strcmp(flag, "--lateral") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d > 5)
        return fail(flag, v, "metres within 0..5");
      o->lateral = d;
    } else if (std::strcmp(flag, "--lighting") == 0) {
      sim::Lighting probe;
      if (!sim::LightingPreset(v, 0, &probe))
        return fail(flag, v, "dawn, noon or overcast");
      o->lighting = v;
    } else if (std::strcmp(flag, "--sun") == 0) {
      char* end = nullptr;
      const double az = std::strtod(v, &end);
      if (end == v || *end != ',')
        return fail(flag, v, "AZ,EL in degrees, e.g. 120,35");
      const char* el_text = end + 1;
      const double el = std::strtod(el_text, &end);
      if (end == el_text || *end != '\0' || !std::isfinite(az) || !(el >= -90 && el <= 90))
        return fail(flag, v, "AZ,EL in degrees with EL within -90..90");
      o->sun_azimuth = az;
      o->sun_elevation = el;
    } else if (std::strcmp(flag, "--clouds") == 0) {
      if (!ParseDouble(v, &d) || d < 0 || d > 1)
        return fail(flag, v, "a cloud cover within 0..1");
      o->clouds = d;
    } else if (std::strcmp(flag, "--exposure") == 0) {
      if (!ParseDouble(v, &d) || std::fabs(d) > 8)
        return fail(flag, v, "stops within -8..8");
      o->exposure = d;
    } else if (std::strcmp(flag, "--width") == 0) {
      if (!ParseInt(v, 8, 8192, &n))
        return fail(flag, v, "pixels within 8..8192");
      o->width = static_cast<int>(n);
      o->size_given = true;
    } else if (std::strcmp(flag, "--height") == 0) {
      if (!ParseInt(v, 8, 8192, &n))
        return fail(flag, v, "pixels within 8..8192");
      o->height = static_cast<int>(n);
      o->size_given = true;
    } else if (std::strcmp(flag, "--camera") == 0) {
      o->camera_file = v;
    } else if (std::strcmp(flag, "--mode") == 0) {
      if (std::strcmp(v, "uv") != 0 && std::strcmp(v, "visible") != 0 &&
          std::strcmp(v, "both") != 0)
        return fail(flag, v, "uv, visible or both");
      o->mode = v;
    } else if (std::strcmp(flag, "--out") == 0) {
      o->out = v;
    } else {
      std::fprintf(stderr, "skyloc simulate: unknown option '%s' (see --help)\n", flag);
      return kExitUsage;
    }
  }
  if (!o->have_world) {
    std::fprintf(stderr,
                 "skyloc simulate: --world is required (seville, city, forest, "
                 "repetitive)\n");
    return kExitUsage;
  }
  if (o->out.empty()) {
    std::fprintf(stderr, "skyloc simulate: --out DIR is required\n");
    return kExitUsage;
  }
  if (o->time_flag != nullptr && (o->spacing || o->jitter)) {
    std::fprintf(stderr,
                 "skyloc simulate: %s samples in time but %s samples in distance: drop %s "
                 "for a fixed frame rate, or drop %s for a frame every --spacing metres\n",
                 o->time_flag, o->spacing ? "--spacing" : "--jitter",
                 o->spacing ? "--spacing" : "--jitter", o->time_flag);
    return kExitUsage;
  }
  if (o->jitter && !o->spacing) {
    std::fprintf(stderr,
                 "skyloc simulate: --jitter applies to distance sampling: add --spacing M (1 "
                 "was the old default), or drop --jitter and shape the speed with --speed-band\n");
    return kExitUsage;
  }
  if (o->size_given && !o->camera_file.empty()) {
    std::fprintf(stderr,
                 "skyloc simulate: --width/--height and --camera both give the image "
                 "size: use one (the camera file's [image] table)\n");
    return kExitUsage;
  }
  return kExitOk;
}

Result<std::string> ReadText(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (f == nullptr)
    return Status::FromErrno(errno, "cannot read '%s'", path.c_str());
  std::string text;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0)
    text.append(buffer, n);
  std::fclose(f);
  return text;
}

// DIR/camera.toml in the camera-file format (docs/CAMERA_FILE.md): a copy of --camera, or
// the default lens written out, its mount included (sim::DefaultSimLens sits turned 90
// degrees on the robot: a replay and its recorded attitude need that frame).
Status WriteCameraFile(const std::string& dir, const Options& o, const dsp::Lens& lens) {
  const std::string path = dir + "/camera.toml";
  if (!o.camera_file.empty()) {
    SKYLOC_TRY_ASSIGN(const std::string text, ReadText(o.camera_file));
    return WriteText(path, "# Copied by skyloc simulate from " + o.camera_file + "\n" + text);
  }
  SKYLOC_TRY_ASSIGN(
      const std::string text,
      drivers::CameraFileText(
          lens, "Written by skyloc simulate: the simulated camera (docs/CAMERA_FILE.md)."));
  return WriteText(path, text);
}

// DIR/simulation.toml: how the run was made, to reproduce or explain it.
Status WriteSimulationToml(const std::string& dir, const Options& o, sim::Spectrum spectrum,
                           const sim::Lighting& lighting, const sim::MotionConfig& motion) {
  char sampling[512];
  if (motion.sampling == sim::Sampling::kDistance) {
    std::snprintf(sampling, sizeof sampling,
                  "sampling = \"distance\"\nframe_spacing_m = %.6f\nspeed_jitter = %.6f\n",
                  motion.frame_spacing_m, motion.speed_jitter);
  } else {
    const sim::SpeedProfile& p = motion.speed;
    std::snprintf(sampling, sizeof sampling,
                  "sampling = \"time\"\nfps = %.6f\ncruise_mps = %.6f\nspeed_band = %.6f\n"
                  "cruise_change_every_m = %.6f\naccel_mps2 = %.6f\nstart_stop_s = %.6f\n"
                  "stops = %d\nstop_seconds = [%.6f, %.6f]\nspeed_ratio = %.6f\n",
                  motion.fps, p.cruise_mps, p.band, p.change_every_m, p.accel_mps2, p.start_stop_s,
                  p.stops, p.stop_min_s, p.stop_max_s, motion.speed_ratio);
  }
  char text[2560];
  std::snprintf(
      text, sizeof text,
      "# Written by skyloc simulate (docs/SIMULATOR.md).\n[world]\nname = \"%s\"\nseed = "
      "%llu\nroute = \"%s\"\n\n[run]\nseed = %llu\nspectrum = \"%s\"\n%scamera_height_m = "
      "%.6f\nstart_m = %.6f\ntilt_deg = %.6f\n"
      "zigzag_deg = %.6f\nzigzag_period_m = %.6f\nbumps_deg = %.6f\nyaw_offset_deg = %.6f\n"
      "lateral_m = %.6f\n"
      "\n[lighting]\npreset = \"%s\"\nsun_azimuth_deg = %.6f\nsun_elevation_deg = %.6f\n"
      "cloud_cover = %.6f\nsky_brightness = %.6f\nexposure_ev = %.6f\nnoise_sigma = %.6f\n"
      "flare = %.6f\n",
      sim::WorldKindName(o.world), static_cast<unsigned long long>(o.seed),
      o.route_file.empty() ? "(the world's own)" : o.route_file.c_str(),
      static_cast<unsigned long long>(o.run), sim::SpectrumName(spectrum), sampling,
      motion.height_m, motion.start_m, motion.tilt_deg, motion.zigzag_deg, motion.zigzag_period_m,
      motion.bumps_deg, motion.yaw_offset_deg, motion.lateral_m, o.lighting.c_str(),
      lighting.sun_azimuth_deg, lighting.sun_elevation_deg, lighting.cloud_cover,
      lighting.sky_brightness, lighting.exposure_ev, lighting.noise_sigma, lighting.flare);
  return WriteText(dir + "/simulation.toml", text);
}

// One output: a camera in one spectrum writing one dataset folder.
struct Output {
  sim::Spectrum spectrum = sim::Spectrum::kUv;
  std::string dir;
  drivers::DatasetWriter writer;
  std::optional<sim::RenderedSource> source;
  std::optional<drivers::SimulatedCamera> camera;
};

class Progress {
 public:
  explicit Progress(std::size_t total) : total_(total), tty_(isatty(STDERR_FILENO) == 1) {}
  void Update(std::size_t done, double seconds) {
    const double fps = seconds > 0 ? static_cast<double>(done) / seconds : 0;
    if (tty_) {
      constexpr int kBar = 30;
      const int filled = static_cast<int>(kBar * done / total_);
      std::fprintf(stderr, "\r[%.*s%.*s] %zu/%zu frames, %.1f frames/s ", filled,
                   "##############################", kBar - filled,
                   "..............................", done, total_, fps);
      if (done == total_)
        std::fprintf(stderr, "\n");
    } else if (done == total_ || done * 10 / total_ != last_decile_) {
      last_decile_ = done * 10 / total_;
      std::fprintf(stderr, "skyloc simulate: %zu/%zu frames, %.1f frames/s\n", done, total_, fps);
    }
  }

 private:
  std::size_t total_;
  bool tty_;
  std::size_t last_decile_ = 0;
};

int Fail(const Status& s) {
  std::fprintf(stderr, "skyloc simulate: %s\n", s.message());
  return kExitFailure;
}

}  // namespace

int RunSimulate(std::span<char* const> args) {
  for (char* const a : args) {
    if (IsHelpFlag(a)) {
      std::fputs(kUsage, stdout);
      return kExitOk;
    }
  }
  Options o;
  if (const int rc = ParseArgs(args, &o); rc != kExitOk)
    return rc;
  const bool seville = o.world == sim::WorldKind::kSeville;

  // The world and its route.
  sim::World world;
  std::vector<sim::Point2> route;
  bool closed = false;
  if (seville) {
    const std::string csv = o.data_dir + "/world5000_triangles.csv";
    const Status s = sim::LoadSevilleWorld(csv.c_str(), &world);
    if (!s.ok()) {
      std::fprintf(stderr,
                   "skyloc simulate: %s\n  (the Seville world ships in the shared data folder; "
                   "point --data at its seville2009 directory)\n",
                   s.message());
      return kExitFailure;
    }
    if (o.route_file.empty())
      o.route_file = o.data_dir + "/routes/ant1_route1.csv";
  } else if (const Status s = sim::MakeProceduralWorld(o.world, o.seed, &world); !s.ok()) {
    return Fail(s);
  }
  if (!o.route_file.empty()) {
    if (const Status s = sim::LoadRouteCsv(o.route_file.c_str(), &route); !s.ok())
      return Fail(s);
  } else {
    route = world.route;
    closed = world.route_closed;
  }

  sim::MotionConfig motion;
  if (o.spacing) {
    motion.sampling = sim::Sampling::kDistance;
    motion.frame_spacing_m = *o.spacing;
    motion.speed_jitter = o.jitter.value_or(motion.speed_jitter);
  } else {
    motion.sampling = sim::Sampling::kTime;
    motion.fps = o.fps.value_or(motion.fps);
    sim::SpeedProfile& p = motion.speed;
    // An ant-sized run: 5 cm frames at 10 fps, as the distance sampling's ant spacing.
    p.cruise_mps = o.speed.value_or(seville ? 0.5 : p.cruise_mps);
    p.band = o.speed_band.value_or(p.band);
    p.accel_mps2 = o.accel.value_or(p.accel_mps2);
    p.start_stop_s = o.start_stop.value_or(p.start_stop_s);
    p.stops = o.stops.value_or(p.stops);
    p.stop_min_s = o.stop_min.value_or(p.stop_min_s);
    p.stop_max_s = o.stop_max.value_or(p.stop_max_s);
  }
  motion.height_m = o.camera_height.value_or(seville ? 0.01 : 1.0);
  motion.tilt_deg = o.tilt;
  motion.zigzag_deg = o.zigzag;
  motion.zigzag_period_m = o.zigzag_period;
  motion.bumps_deg = o.bumps;
  motion.yaw_offset_deg = o.yaw;
  motion.lateral_m = o.lateral;
  motion.start_m = o.start;
  motion.max_frames = o.frames;
  motion.seed = o.run;
  std::vector<sim::TrajectoryPoint> trajectory;
  if (const Status s = sim::BuildTrajectory(route, closed, motion, &trajectory); !s.ok())
    return Fail(Status(s).AddContext("route"));

  sim::Lighting lighting;
  sim::LightingPreset(o.lighting.c_str(), o.run, &lighting);
  lighting.exposure_ev += o.exposure;
  if (o.sun_azimuth)
    lighting.sun_azimuth_deg = *o.sun_azimuth;
  if (o.sun_elevation)
    lighting.sun_elevation_deg = *o.sun_elevation;
  if (o.clouds)
    lighting.cloud_cover = *o.clouds;
  if (!o.flare)
    lighting.flare = 0;

  ManualClock clock;  // unused for stamps: the trajectory's times stamp the frames
  Output storage[2];
  std::size_t count = 0;
  auto add_output = [&](sim::Spectrum spectrum, std::string dir) {
    storage[count].spectrum = spectrum;
    storage[count].dir = std::move(dir);
    ++count;
  };
  if (o.mode == "both") {
    add_output(sim::Spectrum::kUv, o.out + "/uv");
    add_output(sim::Spectrum::kVisible, o.out + "/visible");
  } else {
    add_output(o.mode == "uv" ? sim::Spectrum::kUv : sim::Spectrum::kVisible, o.out);
  }
  const std::span<Output> outputs(storage, count);
  dsp::LensParams lens = sim::DefaultSimLens(o.width, o.height);
  if (!o.camera_file.empty()) {
    Result<dsp::LensParams> loaded = drivers::LoadCameraFile(o.camera_file.c_str());
    if (!loaded.ok())
      return Fail(loaded.status());
    lens = *loaded;
    o.width = lens.width;
    o.height = lens.height;
  }
  for (Output& out : outputs) {
    if (Status s = out.writer.Open(out.dir, /*with_poses=*/true); !s.ok())
      return Fail(s);
    sim::RenderedSourceConfig config;
    config.lens = lens;
    config.spectrum = out.spectrum;
    config.lighting = lighting;
    out.source.emplace(&world, trajectory, config);
    out.camera.emplace(out.source->camera_config(), &*out.source, &clock);
    if (Status s = out.camera->Open(); !s.ok())
      return Fail(s);
    if (Status s = out.camera->Start(); !s.ok())
      return Fail(s);
    if (Status s = WriteCameraFile(out.dir, o, out.source->renderer().lens()); !s.ok())
      return Fail(s);
    if (Status s = WriteSimulationToml(out.dir, o, out.spectrum, lighting, motion); !s.ok())
      return Fail(s);
  }

  std::fprintf(stderr,
               "skyloc simulate: %s world (%zu triangles), %zu frames at %dx%d, mode %s -> %s\n",
               sim::WorldKindName(o.world), world.triangles().size(), trajectory.size(), o.width,
               o.height, o.mode.c_str(), o.out.c_str());
  Progress progress(trajectory.size());
  const auto begin = std::chrono::steady_clock::now();
  double render_s = 0;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    for (Output& out : outputs) {
      const auto t0 = std::chrono::steady_clock::now();
      Result<drivers::Frame> frame = out.camera->Capture(Nanoseconds{0});
      render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!frame.ok())
        return Fail(frame.status());
      if (Status s = out.writer.Append(frame->image, trajectory[i].time_s, frame->pose); !s.ok())
        return Fail(s);
    }
    progress.Update(
        i + 1, std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
  }
  for (Output& out : outputs) {
    if (Status s = out.writer.Close(); !s.ok())
      return Fail(s);
  }
  const double renders = static_cast<double>(trajectory.size() * outputs.size());
  std::printf("skyloc simulate: wrote %zu frames to %s (render %.1f ms/frame at %dx%d)\n",
              trajectory.size(), o.out.c_str(), 1000.0 * render_s / renders, o.width, o.height);
  return kExitOk;
}

}  // namespace skyloc::cli
