// Threads for the offline tools (skyloc eval): dsp/ has none, it exposes independent
// ranges of work (dsp/seqslam_batch.h) and these run them on several cores.
//
// A plain std::thread fork-join, not OpenMP: no compiler runtime to find for each cross
// toolchain and sanitizer build, threads only where eval asks for them, and the firmware
// (which never calls this) links no thread runtime it does not use. The work is a few
// large tasks per call (tens of milliseconds each), so starting the threads per call costs
// nothing measurable.
#pragma once

#include <functional>

#include "skyloc/dsp/seqslam_batch.h"

namespace skyloc::tools {

// Hardware threads (at least 1): the default of --jobs.
int DefaultJobs();

// Runs fn(task, worker) for task = 0 .. tasks - 1 on min(jobs, tasks) threads, the caller's
// thread being worker 0; tasks are handed out in order as workers free up. Returns when
// all are done. Each worker index runs on one thread at a time (for per-worker scratch).
void ParallelFor(int jobs, int tasks, const std::function<void(int task, int worker)>& fn);

// Runs an initialised BlockedSeqSlam on `jobs` threads: per block, the columns in groups of
// BlockedSeqSlam::kColumnGroup, then the searches, in parallel. The result is the
// one-thread Run()'s bit for bit (every float is computed by the same code whatever
// thread runs it). progress(columns matched so far) is called on the caller's thread after
// each block.
void RunBlockedSeqSlam(dsp::BlockedSeqSlam& engine, int jobs,
                       const std::function<void(int)>& progress = {});

}  // namespace skyloc::tools
