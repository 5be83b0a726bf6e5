#include "skyloc/platform/realtime.h"

#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>

namespace skyloc {
namespace {

unsigned long long Limit(int resource) {
  struct rlimit r {};
  if (::getrlimit(resource, &r) != 0)
    return 0;
  return r.rlim_cur == RLIM_INFINITY ? ~0ull : static_cast<unsigned long long>(r.rlim_cur);
}

Status ApplyScheduling(int priority) {
  if (priority <= 0)
    return Status::Ok();
  struct sched_param param {};
  param.sched_priority = priority;
  if (::sched_setscheduler(0, SCHED_FIFO, &param) == 0)
    return Status::Ok();
  const int e = errno;
  return Status::FromErrno(e,
                           "SCHED_FIFO priority %d refused (RLIMIT_RTPRIO is %llu, and no "
                           "CAP_SYS_NICE): run as root, set LimitRTPRIO=%d in the systemd "
                           "unit or 'ulimit -r %d'; continuing with normal scheduling",
                           priority, Limit(RLIMIT_RTPRIO), priority, priority);
}

Status ApplyMemoryLock(bool lock) {
  if (!lock)
    return Status::Ok();
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0)
    return Status::Ok();
  const int e = errno;
  return Status::FromErrno(e,
                           "mlockall refused (RLIMIT_MEMLOCK is %llu bytes, and no "
                           "CAP_IPC_LOCK): set LimitMEMLOCK=infinity in the systemd unit or "
                           "'ulimit -l unlimited'; continuing with pageable memory",
                           Limit(RLIMIT_MEMLOCK));
}

Status ApplyAffinity(int cpu) {
  if (cpu < 0)
    return Status::Ok();
  cpu_set_t set;
  CPU_ZERO(&set);
  if (cpu >= CPU_SETSIZE) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CPU %d is beyond CPU_SETSIZE; "
                         "continuing on any CPU",
                         cpu);
  }
  CPU_SET(static_cast<std::size_t>(cpu), &set);
  if (::sched_setaffinity(0, sizeof set, &set) == 0)
    return Status::Ok();
  const int e = errno;
  return Status::FromErrno(e,
                           "cannot pin to CPU %d (this machine has %ld CPUs online, 0..%ld): "
                           "set [realtime] cpu_affinity to one of them or -1; continuing on "
                           "any CPU",
                           cpu, ::sysconf(_SC_NPROCESSORS_ONLN),
                           ::sysconf(_SC_NPROCESSORS_ONLN) - 1);
}

}  // namespace

RealtimeReport ApplyRealtime(const RealtimeOptions& options) {
  RealtimeReport report;
  report.scheduling = ApplyScheduling(options.sched_fifo_priority);
  report.memory_lock = ApplyMemoryLock(options.lock_memory);
  report.affinity = ApplyAffinity(options.cpu);
  return report;
}

}  // namespace skyloc
