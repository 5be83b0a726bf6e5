// Writes two small dataset folders for the `skyloc eval` integration test: a sideways
// camera sliding along a textured wall, 8 pixels per frame, 40 frames of 64x48. The
// reference run is clean; the query run sees the same places with a different exposure
// (gain and offset, which patch normalisation removes) and pixel noise, 0.5 m to the
// side. Usage: make_eval_datasets OUT_DIR  ->  OUT_DIR/reference, OUT_DIR/query,
// OUT_DIR/gt.csv (query i = reference i).
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "skyloc/drivers/dataset.h"

namespace {

constexpr int kFrames = 40;
constexpr int kWidth = 64;
constexpr int kHeight = 48;
constexpr int kWallWidth = kFrames * 8 + kWidth;

struct Wave {
  double fx, fy, phase, amplitude;
};

int Write(const std::string& dir, const std::vector<Wave>& wall, bool query, unsigned seed) {
  skyloc::drivers::DatasetWriter writer;
  skyloc::Status s = writer.Open(dir, /*with_poses=*/true);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, query ? 6.0 : 0.0);
  std::vector<std::uint8_t> px(static_cast<std::size_t>(kWidth * kHeight));
  for (int f = 0; s.ok() && f < kFrames; ++f) {
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const double wx = f * 8 + x;
        double v = 0.0;
        for (const Wave& w : wall)
          v += w.amplitude * std::sin(w.fx * wx + w.fy * y + w.phase);
        if (query)
          v = 0.7 * v + 20.0 + noise(rng);
        px[static_cast<std::size_t>(y * kWidth + x)] =
            static_cast<std::uint8_t>(std::lround(std::fmin(255.0, std::fmax(0.0, 128.0 + v))));
      }
    }
    const skyloc::drivers::Pose pose{1.0 * f, query ? 0.5 : 0.0, 0.0, 0.0, 0.0, 90.0};
    s = writer.Append(skyloc::dsp::ImageView{px.data(), kWidth, kHeight, kWidth,
                                             skyloc::dsp::PixelFormat::kGrey8},
                      0.1 * f, pose);
  }
  if (s.ok())
    s = writer.Close();
  // The camera file `skyloc eval --method sky` reads for this dataset (docs/CAMERA_FILE.md).
  if (s.ok()) {
    std::FILE* cam = std::fopen((dir + "/camera.toml").c_str(), "w");
    if (cam == nullptr ||
        std::fprintf(cam,
                     "[image]\nwidth = %d\nheight = %d\n\n[lens]\n"
                     "model = \"equidistant\"\nfov_deg = 185.0\n",
                     kWidth, kHeight) < 0 ||
        std::fclose(cam) != 0) {
      std::fprintf(stderr, "make_eval_datasets: cannot write %s/camera.toml\n", dir.c_str());
      return 1;
    }
  }
  if (!s.ok()) {
    std::fprintf(stderr, "make_eval_datasets: %s\n", s.message());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_eval_datasets OUT_DIR\n");
    return 2;
  }
  const std::string out = argv[1];
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> freq(0.05, 0.6), phase(0.0, 6.2831853), amp(10.0, 30.0);
  std::vector<Wave> wall;
  for (int i = 0; i < 12; ++i)
    wall.push_back({freq(rng), freq(rng) - 0.3, phase(rng), amp(rng)});
  if (Write(out + "/reference", wall, false, 1) != 0 || Write(out + "/query", wall, true, 2) != 0)
    return 1;
  std::FILE* gt = std::fopen((out + "/gt.csv").c_str(), "w");
  if (gt == nullptr)
    return 1;
  std::fprintf(gt, "query_index,reference_index\n");
  for (int i = 0; i < kFrames; ++i)
    std::fprintf(gt, "%d,%d\n", i, i);
  return std::fclose(gt) == 0 ? 0 : 1;
}
