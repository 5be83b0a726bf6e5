#include "tools/progress.h"

#include <unistd.h>

#include <utility>

namespace skyloc::tools {
namespace {

using Clock = std::chrono::steady_clock;

std::string Duration(double s) {
  const long t = static_cast<long>(s + 0.5);
  char text[32];
  if (t >= 3600) {
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
  } else {
    std::snprintf(text, sizeof text, "%ld:%02ld", t / 60, t % 60);
  }
  return text;
}

}  // namespace

Progress::Progress(std::string what, std::string unit, long total, int tty, std::FILE* out)
    : what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      tty_(tty < 0 ? ::isatty(::fileno(out)) == 1 : tty != 0),
      out_(out),
      start_(Clock::now()),
      last_(start_) {}

void Progress::Update(long done) {
  const Clock::time_point now = Clock::now();
  const auto interval = tty_ ? std::chrono::milliseconds(250) : std::chrono::milliseconds(10000);
  if (now - last_ < interval || done >= total_)
    return;
  last_ = now;
  Write(done, false);
}

void Progress::Finish() {
  if (tty_ || wrote_)
    Write(total_, true);
}

void Progress::Write(long done, bool final) {
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  const double percent =
      total_ > 0 ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0;
  std::string tail;
  if (final) {
    tail = "done in " + Duration(elapsed);
  } else if (done > 0) {
    tail = Duration(elapsed * static_cast<double>(total_ - done) / static_cast<double>(done)) +
           " left";
  }
  std::fprintf(out_, "%sskyloc eval: %s: %ld / %ld %s (%.0f %%), %s%s", tty_ ? "\r\033[K" : "",
               what_.c_str(), done, total_, unit_.c_str(), percent, tail.c_str(),
               tty_ && !final ? "" : "\n");
  std::fflush(out_);
  wrote_ = true;
}

}  // namespace skyloc::tools
