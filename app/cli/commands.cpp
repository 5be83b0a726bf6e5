#include "cli/commands.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace skyloc::cli {

int UsageError(const char* command, std::string_view what, std::string_view value) {
  std::string message(what);
  if (const std::size_t at = message.find("%s"); at != std::string::npos)
    message.replace(at, 2, value);
  std::fprintf(stderr, "skyloc %s: %s\nRun 'skyloc %s --help' for the options.\n", command,
               message.c_str(), command);
  return kExitUsage;
}

bool ParseFiniteDouble(const char* text, double* out, char** end_out) {
  if (text == nullptr)
    return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (end == text || errno != 0 || !std::isfinite(v))
    return false;
  if (end_out != nullptr)
    *end_out = end;
  else if (*end != '\0')
    return false;
  *out = v;
  return true;
}

}  // namespace skyloc::cli
