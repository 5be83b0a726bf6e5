// How much memory this process holds, for the flat-memory soak test and the exit report.
#pragma once

#include <cstddef>

#include "skyloc/platform/status.h"

namespace skyloc {

// Resident set size in bytes, from /proc/self/statm. Reads into a stack buffer: no
// allocation, so it may be called from an armed AllocationScope.
Result<std::size_t> ResidentSetBytes();

}  // namespace skyloc
