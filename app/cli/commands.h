// The skyloc subcommands. Each is a function taking the arguments after its name and
// returning the process exit code; main() dispatches through kCommands.
#pragma once

#include <cstring>
#include <span>
#include <string_view>

#include "cli/options.h"
#include "firmware/config.h"
#include "skyloc/platform/status.h"

namespace skyloc::cli {

// Every command: the arguments after its name in, the process exit code out.
using CommandMain = int(std::span<char* const> args);

struct Command {
  const char* name;
  const char* summary;
  CommandMain* run;
};

// The robot's commands.
CommandMain RunDemo, RunTeach, RunRepeat, RunReplay, RunRecord, RunRoute, RunDescribe;
// The lab's tools (SKYLOC_TOOLS builds only); RunSurf1dExperiment is `skyloc experiment
// surf1d` (cmd_experiment_surf1d.cpp), its args[0] "surf1d".
CommandMain RunEval, RunSurf1d, RunSimulate, RunExperiment, RunSurf1dExperiment, RunFabmapTrain;

// True for the flags that ask a command for its usage text.
inline bool IsHelpFlag(const char* arg) {
  return std::strcmp(arg, "--help") == 0 || std::strcmp(arg, "-h") == 0;
}

// Which of a simulated run's options a command takes: the run through a configured world
// (teach, repeat, record on camera.kind = "sim") or the whole run (`skyloc simulate`).
enum class SimRunOptions : std::uint8_t { kRun, kWorldAndRun };

// The one place the options of a simulated run are declared: --run, --tilt, --zigzag,
// --bumps, --yaw, --lighting; with kWorldAndRun also --world, --seed, the sampling options
// (--spacing, --jitter; --speed, --speed-band, --accel, --start-stop, --stops,
// --stop-seconds) and --camera-height. Each fills its field of `run`.
void AddSimRunOptions(OptionTable* table, SimRunOptions which, firmware::SimRunConfig* run);

// The one place the sky descriptor's --grid and --normalisation are declared (describe,
// experiment): each fills its field when given. For a firmware::GridPreset and a
// dsp::AmplitudeNormalisation, or std::optional of both (describe's flags).
template <typename Grid, typename Normalisation>
void AddDescriptorChoices(OptionTable* table, Grid* grid, Normalisation* normalisation);

// Exit codes shared by every command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // a runtime error (device, file contents)
inline constexpr int kExitUsage = 2;    // bad command line

// A command's runtime failure: prints "skyloc COMMAND: message" on stderr and returns
// kExitFailure, the one way every command reports one.
int Failed(const char* command, const Status& status);

}  // namespace skyloc::cli
