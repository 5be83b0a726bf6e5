// A fresh folder for one test's files, removed with everything in it when the object goes
// out of scope, so a test that fails halfway leaves no scratch behind in /tmp either.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace skyloc::testing {

class ScratchDir {
 public:
  // Creates <gtest's temporary directory>/<prefix>XXXXXX; path() is empty (and the test
  // has failed) when it cannot.
  explicit ScratchDir(const char* prefix) {
    std::string tmpl = ::testing::TempDir() + prefix + "XXXXXX";
    if (::mkdtemp(tmpl.data()) != nullptr)
      path_ = tmpl;
    else
      ADD_FAILURE() << "cannot create a scratch folder " << tmpl;
  }
  ~ScratchDir() {
    if (path_.empty())
      return;
    std::error_code error;
    std::filesystem::remove_all(path_, error);
    EXPECT_FALSE(error) << "cannot remove " << path_ << ": " << error.message();
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace skyloc::testing
