// The guard of every test and benchmark that opens a socket or a DDS participant: it must
// run in a network namespace of its own whose only interface is the loopback
// (../shared/tools/isolated COMMAND makes one), so nothing it sends can leave the machine.
#pragma once

#include <net/if.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <string>

namespace skyloc::testing {

// Empty when this process is isolated; otherwise what is wrong, and the fix.
inline std::string NetworkIsolationProblem() {
  // A namespace of its own: not the one of the process that started it (ctest, a shell),
  // which runs in the machine's (PID 1's namespace may not be readable in a container).
  struct stat mine = {}, parent = {};
  if (::stat("/proc/self/ns/net", &mine) != 0)
    return "cannot read /proc/self/ns/net";
  const std::string parent_ns = "/proc/" + std::to_string(::getppid()) + "/ns/net";
  if (::stat(parent_ns.c_str(), &parent) == 0 && mine.st_ino == parent.st_ino &&
      mine.st_dev == parent.st_dev)
    return "this process shares its parent's network namespace: run it as "
           "../shared/tools/isolated COMMAND";
  // The interfaces of this namespace (netlink, not /sys, which shows its mounter's).
  struct if_nameindex* interfaces = ::if_nameindex();
  if (interfaces == nullptr)
    return "if_nameindex() failed";
  std::string others;
  for (const struct if_nameindex* i = interfaces; i->if_index != 0; ++i)
    if (std::strcmp(i->if_name, "lo") != 0)
      others += std::string(others.empty() ? "" : ", ") + i->if_name;
  ::if_freenameindex(interfaces);
  if (!others.empty())
    return "this network namespace has interfaces besides the loopback (" + others +
           "): run inside ../shared/tools/isolated";
  return {};
}

}  // namespace skyloc::testing
