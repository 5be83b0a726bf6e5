// Progress of a long offline step on stderr ("vanilla descriptors: 1200 / 7152 frames
// (17 %), 0:42 left"). On a terminal one line is rewritten, at most 4 times a second; when
// stderr is not a terminal (a log file, CI) a line is written at most every 10 seconds, so
// a short run adds nothing and a long one a few lines. Update() from one thread only.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace skyloc::tools {

class Progress {
 public:
  // what: "vanilla descriptors"; unit: "frames". tty: -1 asks isatty(stderr).
  Progress(std::string what, std::string unit, long total, int tty = -1, std::FILE* out = stderr);
  void Update(long done);
  // The final line (terminal: ends the rewritten line; otherwise only after an earlier
  // line was written).
  void Finish();

 private:
  void Write(long done, bool final);

  std::string what_, unit_;
  long total_ = 0;
  bool tty_ = false;
  bool wrote_ = false;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace skyloc::tools
