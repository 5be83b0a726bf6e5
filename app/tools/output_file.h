// Result files of the host commands (eval, experiment, simulate): written whole or not at
// all, so that a full disk or a crash never leaves a truncated plot or table behind.
#pragma once

#include <cstdio>
#include <string>

#include "skyloc/platform/status.h"

namespace skyloc::tools {

// An output file written to a temporary file in the same folder and renamed into place only
// after write + fflush + fsync + fclose succeeded: a full disk or a crash leaves the
// previous file (or none), never a truncated one. Errors name the file and errno's text.
class OutFile {
 public:
  Status Open(const std::string& path);
  std::FILE* get() { return f_; }
  // Flushes, syncs, closes and renames into place; on any failure the temporary file is
  // removed and the previous file, if any, is kept.
  Status Close();
  ~OutFile();

 private:
  void Discard();

  std::string path_;
  std::string tmp_;
  std::FILE* f_ = nullptr;
};

// The whole of `text` as the file at `path`, through an OutFile.
Status WriteText(const std::string& path, const std::string& text);

// printf into a std::string (at most 1023 characters: table lines and plot labels).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace skyloc::tools
