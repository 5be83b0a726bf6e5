// Process signals for the frame loop. The handlers only set flags (sig_atomic_t); the loop
// reads them once per frame:
//   SIGINT, SIGTERM, SIGHUP -> StopRequested(): finish the frame, flush, safe state, exit 0
//                      (SIGHUP: the SSH session of a teach dropped; the route is committed)
//   SIGUSR1         -> TakeReportRequest(): print the latency table, carry on
//   SIGPIPE         -> ignored, so a closed stdout is a write error, not a silent death
//   SIGXFSZ         -> ignored, so a file past RLIMIT_FSIZE is a write error (EFBIG) teach
//                      reports and commits around, not a death with the route uncommitted
// Installed without SA_RESTART, so a blocking wait returns EINTR and the loop sees the
// flag at once rather than after the camera's timeout.
#pragma once

#include "skyloc/platform/status.h"

namespace skyloc {

Status InstallSignalHandlers();
bool StopRequested();
// True once per SIGUSR1 received (several before a call count once).
bool TakeReportRequest();
// The loop's own way to stop (fatal error, end of a dataset); also used by tests.
void RequestStop();
// Clears both flags (tests; a second run in the same process).
void ClearSignalFlags();

}  // namespace skyloc
