// libFuzzer target: the dataset folder's frames.csv parser (drivers/dataset.h). The input
// is parsed from memory, as ReadDataset parses the file's text (the files on disk, read
// and checked for existence around it, are covered by tests/drivers/dataset_test.cpp):
// any input is either rejected with a message naming frames.csv or read into frames whose
// indices count up, whose timestamps do not go backwards and whose pose columns are all
// present or all absent.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "skyloc/drivers/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kCsvPath = "DIR/frames.csv";
  skyloc::drivers::Dataset d;
  const skyloc::Status s = skyloc::drivers::ParseDatasetCsv(
      std::string_view(reinterpret_cast<const char*>(data), size), kCsvPath, &d);
  if (!s.ok()) {
    if (std::strncmp(s.message(), kCsvPath.c_str(), kCsvPath.size()) != 0)
      std::abort();
    return 0;
  }
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    const skyloc::drivers::DatasetFrame& f = d.frames[i];
    if (f.index != static_cast<int>(i) || f.pose.has_value() != d.has_poses ||
        (i > 0 && f.timestamp_s < d.frames[i - 1].timestamp_s))
      std::abort();
  }
  return 0;
}
