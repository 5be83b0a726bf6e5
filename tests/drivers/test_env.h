// How the driver suites find real devices: environment variables the HIL harness sets
// inside the VM (docs/DRIVERS.md lists them). Unset or empty means "no device here".
#pragma once

#include <cstdio>
#include <cstdlib>

namespace skyloc::drivers::testing {

inline const char* Env(const char* name) {
  const char* value = std::getenv(name);
  return (value != nullptr && value[0] != '\0') ? value : nullptr;
}

// Parses "WxH"; leaves the outputs alone when unset or malformed.
inline void EnvSize(const char* name, int* width, int* height) {
  const char* value = Env(name);
  int w = 0;
  int h = 0;
  if (value != nullptr && std::sscanf(value, "%dx%d", &w, &h) == 2 && w > 0 && h > 0) {
    *width = w;
    *height = h;
  }
}

}  // namespace skyloc::drivers::testing
