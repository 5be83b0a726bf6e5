#include "cli/commands.h"

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"

namespace skyloc::cli {

int Failed(const char* command, const Status& status) {
  std::fprintf(stderr, "skyloc %s: %s\n", command, status.message());
  return kExitFailure;
}

void AddSimRunOptions(OptionTable* t, SimRunOptions which, firmware::SimRunConfig* run) {
  if (which == SimRunOptions::kWorldAndRun) {
    t->Custom("--world", "NAME", "seville (needs the shared data folder) or a procedural world",
              [run](const char* text, std::string* expected) {
                sim::WorldKind kind{};
                if (!sim::ParseWorldKind(text, &kind)) {
                  *expected = "seville, city, forest or repetitive";
                  return false;
                }
                run->world.name = sim::WorldKindName(kind);
                return true;
              });
    t->Count("--seed", "N", "procedural world seed (default 1)", &run->world.seed);
  }
  t->Count("--run", "N",
           "run seed: speed profile and stops (or speed jitter), bumps, clouds, sensor noise "
           "(default 1)",
           &run->ride.seed);
  if (which == SimRunOptions::kWorldAndRun) {
    constexpr NumberRange kFraction{0, 1, false, true};
    t->Number("--speed", "M/S", "mean cruise speed (default 1; seville 0.5)", {0, 100, true},
              &run->world.frames.speed.cruise_mps);
    t->Number("--speed-band", "F", "cruise speed varies within (1 +- F) (default 0.3)", kFraction,
              &run->world.frames.speed.band);
    t->Number("--accel", "A", "acceleration and braking, m/s^2 (default 0.5)", {0, 100, true},
              &run->world.frames.speed.accel_mps2);
    t->Number("--start-stop", "S", "seconds standing before the start (default 2)", {0, 3600},
              &run->world.frames.speed.start_stop_s);
    t->Int("--stops", "N", "stops along the route (default 2)", 0, 1000,
           &run->world.frames.speed.stops);
    t->NumberPair(
        "--stop-seconds", "MIN,MAX", "each stop's length, seconds (default 2,6)",
        "MIN,MAX seconds with 0 <= MIN <= MAX <= 3600",
        [](double lo, double hi) { return lo >= 0 && lo <= hi && hi <= 3600; },
        &run->world.frames.speed.stop_min_s, &run->world.frames.speed.stop_max_s);
    t->Number("--spacing", "M",
              "distance sampling instead: a frame every M metres on average (seville: 0.05); "
              "not with the time-sampling options",
              kPositive, &run->world.frames.frame_spacing_m);
    t->Number("--jitter", "F", "with --spacing: speed varies within (1 +- F) (default 0.2)",
              kFraction, &run->world.frames.speed_jitter);
    t->Number("--camera-height", "M", "camera above the ground (default 1, seville 0.01: an ant)",
              kPositive, &run->ride.height_m);
  }
  t->Number("--tilt", "DEG", "constant pitch, nose up positive (the paper's alpha)", {-90, 90},
            &run->ride.tilt_deg);
  t->Number("--zigzag", "DEG", "yaw weave amplitude", {-180, 180}, &run->ride.zigzag_deg);
  t->Number("--bumps", "DEG", "bounded random walk of roll and pitch, up to +-DEG", {0, 45},
            &run->ride.bumps_deg);
  t->Number("--yaw", "DEG", "constant heading offset of the camera", {}, &run->ride.yaw_offset_deg);
  t->Custom("--lighting", "NAME", "dawn, noon (default) or overcast",
            [run](const char* text, std::string* expected) {
              sim::Lighting probe;
              if (!sim::LightingPreset(text, 0, &probe)) {
                *expected = "dawn, noon or overcast";
                return false;
              }
              run->lighting = text;
              return true;
            });
}

template <typename Grid, typename Normalisation>
void AddDescriptorChoices(OptionTable* t, Grid* grid, Normalisation* normalisation) {
  using firmware::GridPreset;
  t->Choice("--grid",
            "the sky descriptor's sampling grid: oversampled (the robot's: the unaliased grid "
            "for 1.5 x the bands; default), auto (the minimal unaliased grid for the bands, "
            "every published table) or paper (2000 points); docs/SKY_DESCRIPTOR.md, \"Grid\"",
            {{firmware::NameOf(GridPreset::kOversampled), GridPreset::kOversampled},
             {firmware::NameOf(GridPreset::kAuto), GridPreset::kAuto},
             {firmware::NameOf(GridPreset::kPaper), GridPreset::kPaper}},
            grid);
  using dsp::AmplitudeNormalisation;
  using dsp::AmplitudeNormalisationName;
  t->Choice(
      "--normalisation",
      "of the sky descriptor's spectrum: unit_l2 (the robot's; default), none (the "
      "paper's eq. 3; the tables measured before 2026-11-26) or divide_by_a0",
      {{AmplitudeNormalisationName(AmplitudeNormalisation::kUnitL2),
        AmplitudeNormalisation::kUnitL2},
       {AmplitudeNormalisationName(AmplitudeNormalisation::kNone), AmplitudeNormalisation::kNone},
       {AmplitudeNormalisationName(AmplitudeNormalisation::kDivideByA0),
        AmplitudeNormalisation::kDivideByA0}},
      normalisation);
}
template void AddDescriptorChoices(OptionTable*, firmware::GridPreset*,
                                   dsp::AmplitudeNormalisation*);
template void AddDescriptorChoices(OptionTable*, std::optional<firmware::GridPreset>*,
                                   std::optional<dsp::AmplitudeNormalisation>*);

}  // namespace skyloc::cli
