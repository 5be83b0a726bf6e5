// The outputs' tests open sockets (and, with Cyclone DDS, a participant): they start only
// inside a network namespace of their own with nothing but the loopback (CTest runs this
// program through ../shared/tools/isolated).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "support/network_namespace.h"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const std::string problem = skyloc::testing::NetworkIsolationProblem();
  if (!problem.empty()) {
    std::fprintf(stderr, "skyloc_outputs_tests: refusing to start: %s\n", problem.c_str());
    return 1;
  }
  return RUN_ALL_TESTS();
}
