// The skyloc subcommands. Each is a function taking the arguments after its name and
// returning the process exit code; main() dispatches through kCommands.
#pragma once

#include <cstring>
#include <span>

namespace skyloc::app {

using CommandFn = int (*)(std::span<char* const> args);

struct Command {
  const char* name;
  const char* summary;
  CommandFn run;
};

int RunDemo(std::span<char* const> args);
int RunTeach(std::span<char* const> args);
int RunRepeat(std::span<char* const> args);
int RunReplay(std::span<char* const> args);
int RunRecord(std::span<char* const> args);
int RunRoute(std::span<char* const> args);
int RunEval(std::span<char* const> args);
int RunDescribe(std::span<char* const> args);
int RunSurf1d(std::span<char* const> args);
int RunSimulate(std::span<char* const> args);
int RunExperiment(std::span<char* const> args);
int RunFabmapTrain(std::span<char* const> args);

// True for the flags that ask a command for its usage text.
inline bool IsHelpFlag(const char* arg) {
  return std::strcmp(arg, "--help") == 0 || std::strcmp(arg, "-h") == 0;
}

// Exit codes shared by every command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // a runtime error (device, file contents)
inline constexpr int kExitUsage = 2;    // bad command line

}  // namespace skyloc::app
