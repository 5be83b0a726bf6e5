// libFuzzer target: the dataset folder's frames.csv reader (drivers/dataset.h). The input
// is written as DIR/frames.csv next to a frames/ folder holding two tiny images; any input
// is either rejected with a message naming frames.csv or read into frames whose indices
// count up and whose pose columns are all present or all absent.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/image_file.h"

namespace {

// The scratch folder, removed when the fuzzer exits normally.
struct ScratchDir {
  std::string path;
  ~ScratchDir() {
    for (const char* name : {"/frames/000000.png", "/frames/000001.png", "/frames.csv"})
      std::remove((path + name).c_str());
    ::rmdir((path + "/frames").c_str());
    ::rmdir(path.c_str());
  }
};

std::string MakeDir() {
  char tmpl[] = "/tmp/skyloc_dataset_fuzz_XXXXXX";
  if (::mkdtemp(tmpl) == nullptr)
    std::abort();
  const std::string dir = tmpl;
  if (::mkdir((dir + "/frames").c_str(), 0755) != 0)
    std::abort();
  std::uint8_t pixels[16] = {};
  const skyloc::dsp::ImageView image{pixels, 4, 4, 4, skyloc::dsp::PixelFormat::kGrey8};
  for (const char* name : {"/frames/000000.png", "/frames/000001.png"}) {
    if (!skyloc::drivers::SavePng((dir + name).c_str(), image).ok())
      std::abort();
  }
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const ScratchDir scratch{MakeDir()};
  const std::string& dir = scratch.path;
  const std::string csv = dir + "/frames.csv";
  std::FILE* f = std::fopen(csv.c_str(), "wb");
  if (f == nullptr || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0)
    std::abort();
  skyloc::Result<skyloc::drivers::Dataset> d = skyloc::drivers::ReadDataset(dir);
  if (!d.ok()) {
    if (d.status().message()[0] == '\0')
      std::abort();
    return 0;
  }
  for (std::size_t i = 0; i < d->frames.size(); ++i) {
    if (d->frames[i].index != static_cast<int>(i) || d->frames[i].pose.has_value() != d->has_poses)
      std::abort();
  }
  return 0;
}
