// Optional real-time setup of the frame-loop process: SCHED_FIFO priority, locked memory,
// CPU affinity. Each is attempted independently; one that is refused yields a warning
// naming the missing permission or limit and how to grant it, and the firmware carries on
// without it (a robot that localises a little late beats one that does not start).
#pragma once

#include "skyloc/platform/status.h"

namespace skyloc {

struct RealtimeOptions {
  int sched_fifo_priority = 0;  // 1..99; 0 leaves the scheduler alone
  bool lock_memory = false;     // mlockall(MCL_CURRENT | MCL_FUTURE)
  int cpu = -1;                 // pin to this CPU; -1 leaves the affinity alone
};

struct RealtimeReport {
  // OK when applied or not requested; otherwise the warning to print.
  Status scheduling;
  Status memory_lock;
  Status affinity;
  bool all_ok() const { return scheduling.ok() && memory_lock.ok() && affinity.ok(); }
};

RealtimeReport ApplyRealtime(const RealtimeOptions& options);

}  // namespace skyloc
