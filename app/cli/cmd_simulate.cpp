// `skyloc simulate`: renders a run through a simulated world and writes it as a dataset
// folder (docs/DATASETS.md) with ground-truth poses, for eval, replay, the experiments
// and the demo. docs/SIMULATOR.md describes the worlds, renderer and options.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "firmware/sim_run.h"
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

constexpr const char* kDescription =
    "Renders a run of an upward fisheye camera through a simulated world and writes a\n"
    "dataset folder: DIR/frames/NNNNNN.png, DIR/frames.csv (with poses), DIR/camera.toml\n"
    "(the lens, docs/CAMERA_FILE.md) and DIR/simulation.toml (how the run was made).\n"
    "With --mode both: DIR/uv/ and DIR/visible/, the same poses in both.\n"
    "Sampling: in time by default, a frame every 1/fps s along a speed profile (--fps,\n"
    "--speed, --speed-band, --accel, --start-stop, --stops, --stop-seconds); --spacing\n"
    "samples in distance instead (with --jitter). Without --route: the world's own route,\n"
    "for seville routes/ant1_route1.csv. The default image is 320x240 through an\n"
    "equidistant 185-degree lens whose circle fills the shorter side.\n";

// The time-sampling options: none of them goes with distance sampling (--spacing).
constexpr const char* kTimeOptions[] = {"--fps",        "--speed", "--speed-band",  "--accel",
                                        "--start-stop", "--stops", "--stop-seconds"};

struct Options {
  firmware::SimRunConfig run;
  std::string route_file;
  std::string data_dir = "../shared/data/seville2009";
  double fps = sim::MotionConfig{}.fps;
  // simulate's own motion options (--zigzag-period, --lateral, --start, --frames); the run
  // gives the rest of the motion (firmware::SimMotionConfig).
  sim::MotionConfig motion;
  double exposure = 0;
  double sun_azimuth = 0, sun_elevation = 0, clouds = 0;
  bool sun_given = false, clouds_given = false;  // else the lighting preset's
  bool no_flare = false;
  int width = 320, height = 240;
  std::string camera_file;
  std::string mode = "uv";
  std::string out;
};

// Parses and checks the command line; kRun or the outcome to exit with.
ParseOutcome ParseArgs(std::span<char* const> args, Options* o) {
  o->run = firmware::SimulateDefaults(/*seville=*/false);
  o->run.world.name.clear();  // --world is required
  OptionTable t("simulate", "--world NAME --out DIR [options]", kDescription);
  t.Text("--out", "DIR", "the dataset folder to write", &o->out);
  t.Text("--route", "FILE", "route CSV (x_cm,y_cm,... or x_m,y_m,...)", &o->route_file);
  t.Text("--data", "DIR", "Seville data folder (default ../shared/data/seville2009)", &o->data_dir);
  // Time sampling's frame rate leads the sampling options (the run's own follow).
  t.Number("--fps", "N", "camera frame rate (default 10)", {0, 1000, true}, &o->fps);
  AddSimRunOptions(&t, SimRunOptions::kWorldAndRun, &o->run);
  t.Number("--zigzag-period", "M", "route distance of one zigzag weave (default 20)", kPositive,
           &o->motion.zigzag_period_m);
  t.Number("--lateral", "M",
           "wander sideways off the route within +-M metres, a drift over 40-80 m and a weave "
           "over 12-25 m: a second drive never retraces the first (default 0)",
           {0, 5}, &o->motion.lateral_m);
  t.Number("--start", "M", "start this far along the route (default 0)", {0}, &o->motion.start_m);
  t.Int("--frames", "N", "at most N frames (default: the whole route)", 1, 10'000'000,
        &o->motion.max_frames);
  t.NumberPair(
      "--sun", "AZ,EL", "sun azimuth (counter-clockwise from east) and elevation, degrees",
      "AZ,EL in degrees with EL within -90..90",
      [](double, double el) { return el >= -90 && el <= 90; }, &o->sun_azimuth, &o->sun_elevation);
  t.Number("--clouds", "F", "cloud cover 0 (clear) .. 1 (overcast)", {0, 1}, &o->clouds);
  t.Number("--exposure", "EV", "exposure offset in stops, added to the preset's", {-8, 8},
           &o->exposure);
  t.Flag("--no-flare", "no lens flare", &o->no_flare);
  t.Int("--width", "W", "image width of the default lens (default 320)", 8, 8192, &o->width);
  t.Int("--height", "H", "image height of the default lens (default 240)", 8, 8192, &o->height);
  t.Text("--camera", "FILE", "a camera file (docs/CAMERA_FILE.md) instead: size, lens, mount",
         &o->camera_file);
  t.Choice<std::string>("--mode", "uv (default), visible or both",
                        {{"uv", "uv"}, {"visible", "visible"}, {"both", "both"}}, &o->mode);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  if (o->run.world.name.empty())
    return t.Refuse("--world is required (seville, city, forest, repetitive)");
  if (o->out.empty())
    return t.Refuse("--out DIR is required");
  const char* time_option = nullptr;
  for (const char* name : kTimeOptions)
    time_option = time_option == nullptr && t.Given(name) ? name : time_option;
  const bool spacing = t.Given("--spacing"), jitter = t.Given("--jitter");
  if (time_option != nullptr && (spacing || jitter)) {
    const char* distance_option = spacing ? "--spacing" : "--jitter";
    return t.Refuse(std::string(time_option) + " samples in time but " + distance_option +
                    " samples in distance: drop " + distance_option +
                    " for a fixed frame rate, or drop " + time_option +
                    " for a frame every --spacing metres");
  }
  if (jitter && !spacing)
    return t.Refuse(
        "--jitter applies to distance sampling: add --spacing M (1 was the old default), or "
        "drop --jitter and shape the speed with --speed-band");
  if ((t.Given("--width") || t.Given("--height")) && !o->camera_file.empty())
    return t.Refuse(
        "--width/--height and --camera both give the image size: use one (the camera file's "
        "[image] table)");
  if (spacing)
    o->run.world.frames.sampling = sim::Sampling::kDistance;
  if (o->run.world.name == "seville") {  // an ant's run unless told otherwise
    const firmware::SimRunConfig ant = firmware::SimulateDefaults(/*seville=*/true);
    if (!t.Given("--speed"))
      o->run.world.frames.speed.cruise_mps = ant.world.frames.speed.cruise_mps;
    if (!t.Given("--camera-height"))
      o->run.ride.height_m = ant.ride.height_m;
  }
  o->sun_given = t.Given("--sun");
  o->clouds_given = t.Given("--clouds");
  return ParseOutcome::kRun;
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
      o.run.world.name.c_str(), static_cast<unsigned long long>(o.run.world.seed),
      o.route_file.empty() ? "(the world's own)" : o.route_file.c_str(),
      static_cast<unsigned long long>(o.run.ride.seed), sim::SpectrumName(spectrum), sampling,
      motion.height_m, motion.start_m, motion.tilt_deg, motion.zigzag_deg, motion.zigzag_period_m,
      motion.bumps_deg, motion.yaw_offset_deg, motion.lateral_m, o.run.lighting.c_str(),
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

// The run's lighting preset, with the options that override it piecewise.
Result<sim::Lighting> Lighting(const Options& o) {
  SKYLOC_TRY_ASSIGN(sim::Lighting lighting, firmware::SimLighting(o.run));
  lighting.exposure_ev += o.exposure;
  if (o.sun_given) {
    lighting.sun_azimuth_deg = o.sun_azimuth;
    lighting.sun_elevation_deg = o.sun_elevation;
  }
  if (o.clouds_given)
    lighting.cloud_cover = o.clouds;
  if (o.no_flare)
    lighting.flare = 0;
  return lighting;
}

int Simulate(Options& o) {
  sim::WorldKind world_kind{};
  sim::ParseWorldKind(o.run.world.name.c_str(), &world_kind);  // --world accepted only these
  const bool seville = world_kind == sim::WorldKind::kSeville;

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
  } else if (const Status s = sim::MakeProceduralWorld(world_kind, o.run.world.seed, &world);
             !s.ok()) {
    return Failed("simulate", s);
  }
  if (!o.route_file.empty()) {
    if (const Status s = sim::LoadRouteCsv(o.route_file.c_str(), &route); !s.ok())
      return Failed("simulate", s);
  } else {
    route = world.route;
    closed = world.route_closed;
  }

  const sim::MotionConfig motion = firmware::SimMotionConfig(o.run, o.fps, o.motion);
  std::vector<sim::TrajectoryPoint> trajectory;
  if (const Status s = sim::BuildTrajectory(route, closed, motion, &trajectory); !s.ok())
    return Failed("simulate", Status(s).AddContext("route"));

  Result<sim::Lighting> lighting = Lighting(o);
  if (!lighting.ok())
    return Failed("simulate", lighting.status());

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
      return Failed("simulate", loaded.status());
    lens = *loaded;
    o.width = lens.width;
    o.height = lens.height;
  }
  for (Output& out : outputs) {
    if (Status s = out.writer.Open(out.dir, /*with_poses=*/true); !s.ok())
      return Failed("simulate", s);
    sim::RenderedSourceConfig config;
    config.lens = lens;
    config.spectrum = out.spectrum;
    config.lighting = *lighting;
    out.source.emplace(&world, trajectory, config);
    out.camera.emplace(out.source->camera_config(), &*out.source, &clock);
    if (Status s = out.camera->Open(); !s.ok())
      return Failed("simulate", s);
    if (Status s = out.camera->Start(); !s.ok())
      return Failed("simulate", s);
    if (Status s = WriteCameraFile(out.dir, o, out.source->renderer().lens()); !s.ok())
      return Failed("simulate", s);
    if (Status s = WriteSimulationToml(out.dir, o, out.spectrum, *lighting, motion); !s.ok())
      return Failed("simulate", s);
  }

  std::fprintf(stderr,
               "skyloc simulate: %s world (%zu triangles), %zu frames at %dx%d, mode %s -> %s\n",
               o.run.world.name.c_str(), world.triangles().size(), trajectory.size(), o.width,
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
        return Failed("simulate", frame.status());
      if (Status s = out.writer.Append(frame->image, trajectory[i].time_s, frame->pose); !s.ok())
        return Failed("simulate", s);
    }
    progress.Update(
        i + 1, std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
  }
  for (Output& out : outputs) {
    if (Status s = out.writer.Close(); !s.ok())
      return Failed("simulate", s);
  }
  const double renders = static_cast<double>(trajectory.size() * outputs.size());
  std::printf("skyloc simulate: wrote %zu frames to %s (render %.1f ms/frame at %dx%d)\n",
              trajectory.size(), o.out.c_str(), 1000.0 * render_s / renders, o.width, o.height);
  return kExitOk;
}

}  // namespace

int RunSimulate(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, Simulate);
}

}  // namespace skyloc::cli
