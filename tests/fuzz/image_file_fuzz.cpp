// libFuzzer target: the image reader (drivers/image_file.h), PNG through stb and binary
// PGM/PPM read directly. Any input is either refused with a message naming the file or
// decoded into an image of a supported format whose every pixel can be read.
//
// LoadImage reads a path, so each input is written to one memory file (memfd) that is
// read back through /proc/self/fd: no scratch folder, nothing left on disk.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "skyloc/drivers/image_file.h"

namespace {

struct MemoryFile {
  int fd = -1;
  std::string path;
  MemoryFile() {
    fd = ::memfd_create("skyloc_image_fuzz", 0);
    if (fd < 0)
      std::abort();
    path = "/proc/self/fd/" + std::to_string(fd);
  }
  ~MemoryFile() { ::close(fd); }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const MemoryFile file;
  if (::ftruncate(file.fd, 0) != 0 ||
      ::pwrite(file.fd, data, size, 0) != static_cast<ssize_t>(size))
    std::abort();
  const skyloc::Result<skyloc::drivers::OwnedImage> image =
      skyloc::drivers::LoadImage(file.path.c_str());
  if (!image.ok()) {
    // The message names the file, so a user knows which of many frames is bad.
    if (std::strstr(image.status().message(), file.path.c_str()) == nullptr) {
      std::fprintf(stderr, "error without the file name: %s\n", image.status().message());
      std::abort();
    }
    return 0;
  }
  const skyloc::dsp::ImageView view = image.value().view();
  const int channels = view.format == skyloc::dsp::PixelFormat::kGrey8   ? 1
                       : view.format == skyloc::dsp::PixelFormat::kRgb24 ? 3
                                                                         : 0;
  if (channels == 0 || view.width <= 0 || view.height <= 0 ||
      view.stride != static_cast<std::size_t>(view.width) * static_cast<std::size_t>(channels))
    std::abort();
  // Every pixel is read: ASan checks the buffer holds what the view promises.
  std::uint64_t sum = 0;
  for (int y = 0; y < view.height; ++y) {
    const std::uint8_t* row = view.Row(y);
    for (std::size_t x = 0; x < view.stride; ++x)
      sum += row[x];
  }
  if (sum > std::uint64_t{255} * view.stride * static_cast<std::uint64_t>(view.height))
    std::abort();
  return 0;
}
