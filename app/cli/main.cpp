#include <cstdio>
#include <cstring>
#include <span>

#include "cli/commands.h"

namespace skyloc::cli {
namespace {

// The robot's commands, then the lab's (built with SKYLOC_TOOLS only: the firmware-only
// ARM binary neither lists nor knows them).
constexpr Command kCommands[] = {
    {"demo", "localise on the simulated camera and print what happened", RunDemo},
    {"teach", "record a route's sky descriptors into a route database", RunTeach},
    {"repeat", "localise live against a taught route (one JSON line per frame)", RunRepeat},
    {"replay", "run a recorded dataset through the repeat pipeline", RunReplay},
    {"record", "record the camera into a dataset folder for replay and eval", RunRecord},
    {"route", "inspect or recover a route database file", RunRoute},
    {"describe", "print the sky descriptor (threshold, sky fraction, SH amplitudes) of images",
     RunDescribe},
#if SKYLOC_WITH_TOOLS
    {"eval", "match a query run against a reference run and score it (PR, plots)", RunEval},
    {"surf1d", "1D SURF between two images: features, matches, scores and relative heading",
     RunSurf1d},
    {"simulate", "render a run through a simulated world into a dataset folder", RunSimulate},
    {"experiment", "run one of the paper's experiments on simulated runs", RunExperiment},
    {"fabmap-train", "train the FAB-MAP 2.0 vocabulary for eval --method fabmap", RunFabmapTrain},
#endif
};

void PrintUsage(std::FILE* out) {
  std::fprintf(out, "usage: skyloc COMMAND [ARGS...]\n\ncommands:\n");
  for (const Command& c : kCommands)
    std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(out, "\n'skyloc COMMAND --help' describes a command.\n");
}

}  // namespace
}  // namespace skyloc::cli

int main(int argc, char** argv) {
  using namespace skyloc::cli;
  if (argc < 2) {
    PrintUsage(stderr);
    return kExitUsage;
  }
  const char* name = argv[1];
  if (IsHelpFlag(name) || std::strcmp(name, "help") == 0) {
    PrintUsage(stdout);
    return kExitOk;
  }
  if (std::strcmp(name, "--version") == 0 || std::strcmp(name, "version") == 0) {
    std::printf("skyloc %s\n", SKYLOC_VERSION);
    return kExitOk;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(name, c.name) == 0) {
      return c.run(std::span<char* const>(argv + 2, static_cast<std::size_t>(argc - 2)));
    }
  }
  std::fprintf(stderr, "skyloc: unknown command '%s'. Run 'skyloc --help' for the list.\n", name);
  return kExitUsage;
}
