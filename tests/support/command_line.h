// A command line for the option parser's tests: owns its words and hands out the
// char* view that main() would.
#pragma once

#include <span>
#include <string>
#include <utility>
#include <vector>

namespace skyloc::testing {

struct CommandLine {
  explicit CommandLine(std::vector<std::string> words) : storage(std::move(words)) {
    for (std::string& w : storage)
      pointers.push_back(w.data());
  }
  std::span<char* const> span() const { return pointers; }
  std::vector<std::string> storage;
  std::vector<char*> pointers;
};

}  // namespace skyloc::testing
