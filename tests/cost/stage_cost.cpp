// stage_cost: runs one stage of the firmware's frame path a given number of times, and
// nothing else, so an instruction counter outside the program (tests/cost/count_instructions.py
// under qemu-user, or callgrind) measures that stage exactly. Set-up (the lens table, the SH
// tables, a route of N frames) costs the same whatever the count, so the counter runs each
// stage for R and 2R repetitions and takes the difference: the instructions of R repetitions
// with the set-up subtracted. Not a benchmark: it measures no time.
//
//   stage_cost STAGE[@BANDS][+wWfF] REPETITIONS [ROUTE_FRAMES [STORAGE [IMAGE_DIR]]]
//
// STORAGE: how the route filter holds the route ([capacities] route_storage, spelled by the
// configuration's own table through firmware::ValueOf); float32 when left out. It applies
// to the filter and frame stages.
// @BANDS sets [descriptor] bands on the default (oversampled) grid, e.g. frame@120: the
// descriptor the robot would run with more bands, measured the same way.
// +wWfF sets the route filter's search window ([seqslam] search_window W, refresh_frames F;
// route_filter.h, 6.), e.g. frame+w128f10 or filter@64+w128f10: each step compares the
// rows within +-W of the last best row and a slice of N / F rows, after the first step
// (every row), which the counter's R / 2R difference cancels.
//
// Stages (the default configuration, config/skyloc.toml, one 640x480 grey frame):
//   segmentation  the Otsu threshold of the frame (histogram over the lens's visible pixels)
//   descriptor    the whole sky descriptor: segmentation, samples, SH projection, amplitudes
//   strip         the horizon strip for the heading ([heading] strip_columns)
//   heading       dsp::HeadingEstimator on two strips ([heading] defaults: correlation + SURF)
//   correlation   the same with surf = false (the cross-correlation only)
//   heading_surf  the same with 1D SURF on every pair (surf_every_frame): the cost of a frame
//                 whose correlation is uncertain; the stored and the query strip swap every
//                 repetition, so the stored strip is never the previous one
//   filter        one dsp::RouteFilter step against ROUTE_FRAMES rows (the default matcher)
//   frame         firmware::Pipeline::Localise: descriptor + strip + filter + state + heading
//   frame_noheading  the same with [heading] off (no strips in the route, no heading)
//   render        renders the street frames into IMAGE_DIR for the stages above (set-up only)
// It prints what it ran and a checksum of the results (so no stage can be optimised away).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "firmware/pipeline.h"
#include "skyloc/dsp/heading.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/segmentation.h"
#include "skyloc/sim/street_source.h"

namespace {

using namespace skyloc;
using namespace skyloc::firmware;

constexpr int kWidth = 640, kHeight = 480, kImages = 2;

int Fail(const char* what) {
  std::fprintf(stderr, "stage_cost: %s\n", what);
  return 1;
}

// kImages frames of the simulated street (the descriptor's cost depends a little on the
// sky's shape: the segmentation's histogram is the same work for any frame, Otsu's search
// too). Rendering them is most of the set-up's instructions, and the counter runs under qemu
// with every block logged: `stage_cost render 0 0 float32 DIR` renders them once into DIR
// (street0.grey, street1.grey: 640x480 bytes), and the other stages read them from there
// when given DIR.
std::string ImagePath(const std::string& dir, int i) {
  return dir + "/street" + std::to_string(i) + ".grey";
}

bool RenderImages(std::vector<std::vector<std::uint8_t>>* images) {
  sim::StreetOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.seed = 5;
  o.frames = kImages;
  sim::FilmedStreet filmed(o);
  drivers::Camera& camera = filmed.camera;
  if (!camera.Open().ok() || !camera.Start().ok())
    return false;
  for (int i = 0; i < kImages; ++i) {
    Result<drivers::Frame> f = camera.Capture(std::chrono::seconds(1));
    if (!f.ok())
      return false;
    images->emplace_back(f->image.data, f->image.data + kWidth * kHeight);
  }
  return true;
}

bool ReadImages(const std::string& dir, std::vector<std::vector<std::uint8_t>>* images) {
  for (int i = 0; i < kImages; ++i) {
    std::vector<std::uint8_t> image(static_cast<std::size_t>(kWidth * kHeight));
    std::FILE* f = std::fopen(ImagePath(dir, i).c_str(), "rb");
    if (f == nullptr)
      return false;
    const std::size_t got = std::fread(image.data(), 1, image.size(), f);
    std::fclose(f);
    if (got != image.size())
      return false;
    images->push_back(std::move(image));
  }
  return true;
}

bool WriteImages(const std::string& dir, const std::vector<std::vector<std::uint8_t>>& images) {
  for (int i = 0; i < kImages; ++i) {
    std::FILE* f = std::fopen(ImagePath(dir, i).c_str(), "wb");
    if (f == nullptr)
      return false;
    const std::size_t put = std::fwrite(images[static_cast<std::size_t>(i)].data(), 1,
                                        images[static_cast<std::size_t>(i)].size(), f);
    if (std::fclose(f) != 0 || put != images[static_cast<std::size_t>(i)].size())
      return false;
  }
  return true;
}

dsp::ImageView View(const std::vector<std::uint8_t>& image) {
  return {image.data(), kWidth, kHeight, static_cast<std::size_t>(kWidth),
          dsp::PixelFormat::kGrey8};
}

// Route frame i: random amplitudes in [0, 1) (no two alike, so FinishRoute merges no rows and
// the step scans all N; the step's work does not depend on the values). xorshift32, seeded
// per frame: a cheap generator keeps the set-up of a 100,000-frame route short under qemu.
void RouteDescriptor(int i, std::vector<float>* d) {
  std::uint32_t x = 2463534242u ^ (static_cast<std::uint32_t>(i) * 2654435761u);
  for (float& v : *d) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    v = static_cast<float>(x >> 8) * 0x1p-24f;
  }
}

// The bytes one route filter step reads and writes per route row (descriptor as held,
// with its exponent byte for codes; frame numbers, cost and difference columns), for the
// cost model's memory term.
// With the search window, the descriptors of at most 2 W + 1 + ceil(N / F) rows, and the
// columns of all N.
std::size_t ScanBytes(int route_frames, int dim, dsp::ReferenceStorage storage,
                      const dsp::RouteFilterParams& filter) {
  const std::size_t n = static_cast<std::size_t>(route_frames);
  const std::size_t row = dsp::RouteFilter::BytesPerReference(dim, storage);
  if (filter.search_window == 0 || 2 * static_cast<std::size_t>(filter.search_window) + 1 >= n)
    return n * row;
  const std::size_t f = static_cast<std::size_t>(filter.refresh_frames);
  const std::size_t compared =
      2 * static_cast<std::size_t>(filter.search_window) + 1 + (n + f - 1) / f;
  const std::size_t descriptor = dsp::ReferenceRowBytes(storage, dim);
  return std::min(compared, n) * descriptor + n * (row - descriptor);
}

// " search window W refresh F" (rows each side, frames) for the output line, or nothing.
std::string WindowText(const dsp::RouteFilterParams& filter) {
  if (filter.search_window == 0)
    return "";
  return " search window " + std::to_string(filter.search_window) + " refresh " +
         std::to_string(filter.refresh_frames);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3)
    return Fail(
        "usage: stage_cost STAGE[@BANDS][+wWfF] REPETITIONS [ROUTE_FRAMES [STORAGE [IMAGE_DIR]]]");
  std::string stage = argv[1];
  int search_window = 0, refresh_frames = 0;
  if (const std::size_t plus = stage.find('+'); plus != std::string::npos) {
    char end = 0;
    if (std::sscanf(stage.c_str() + plus, "+w%df%d%c", &search_window, &refresh_frames, &end) != 2)
      return Fail("STAGE+wWfF: e.g. frame+w128f10");
    stage.resize(plus);
  }
  int bands = 0;  // 0: the default configuration's
  if (const std::size_t at = stage.find('@'); at != std::string::npos) {
    bands = static_cast<int>(std::strtol(stage.c_str() + at + 1, nullptr, 10));
    stage.resize(at);
    if (bands < 1)
      return Fail("STAGE@BANDS: BANDS >= 1");
  }
  const bool with_heading = stage != "frame_noheading";
  if (!with_heading)
    stage = "frame";
  const long repetitions = std::strtol(argv[2], nullptr, 10);
  const int route_frames = argc > 3 ? static_cast<int>(std::strtol(argv[3], nullptr, 10)) : 10000;
  dsp::ReferenceStorage storage = dsp::ReferenceStorage::kFloat32;
  if (argc > 4 && !ValueOf(argv[4], &storage))
    return Fail(("unknown route storage \"" + std::string(argv[4]) + "\": one of " +
                 NamesOf<dsp::ReferenceStorage>())
                    .c_str());
  const std::string image_dir = argc > 5 ? argv[5] : "";
  if (repetitions < 0 || route_frames < 1)
    return Fail("REPETITIONS >= 0 and ROUTE_FRAMES >= 1");

  Config config = DefaultConfig();
  config.seqslam.filter.search_window = search_window;
  config.seqslam.filter.refresh_frames = refresh_frames;
  if (dsp::ValidateRouteFilterParams(config.seqslam.filter) != dsp::SeqSlamError::kOk)
    return Fail(dsp::SeqSlamErrorMessage(dsp::ValidateRouteFilterParams(config.seqslam.filter)));
  config.capacities.route_frames = route_frames;
  config.capacities.route_storage = storage;
  if (bands > 0) {
    config.descriptor.bands = bands;
    ResolveDescriptorGrid(&config.descriptor);  // the grid for these bands
  }
  if (!with_heading)
    config.heading.strip.n_azimuth = 0;
  const bool heading_stage =
      stage == "heading" || stage == "correlation" || stage == "strip" || stage == "heading_surf";
  if (stage == "descriptor" || stage == "segmentation")
    config.heading.strip.n_azimuth = 0;  // Describe() without the strip
  if (stage == "correlation")
    config.heading.estimate.surf = false;
  if (stage == "heading_surf")
    config.heading.estimate.surf_every_frame = true;
  double checksum = 0;
  if (stage == "render") {
    std::vector<std::vector<std::uint8_t>> images;
    if (image_dir.empty() || !RenderImages(&images) || !WriteImages(image_dir, images))
      return Fail("render: cannot render the street or write its frames into IMAGE_DIR");
    return 0;
  }
  if (stage == "filter") {
    // The route filter alone, as Pipeline::Init configures it (no pipeline, no frames).
    dsp::RouteFilter filter;
    const int dim = config.descriptor.bands;
    if (filter.Init(config.seqslam.filter, dim, route_frames, storage) != dsp::SeqSlamError::kOk)
      return Fail("filter Init");
    std::vector<float> d(static_cast<std::size_t>(dim));
    for (int i = 0; i < route_frames; ++i) {
      RouteDescriptor(i, &d);
      (void)filter.AddReference(d);
    }
    if (filter.FinishRoute() != dsp::SeqSlamError::kOk)
      return Fail("FinishRoute");
    if (filter.rows() != route_frames)
      return Fail("FinishRoute merged rows: the step would not scan ROUTE_FRAMES rows");
    for (long r = 0; r < repetitions; ++r) {
      RouteDescriptor(static_cast<int>((r * 37) % route_frames), &d);
      dsp::SeqSlamMatch match;
      (void)filter.Step(d, &match);
      checksum += static_cast<double>(match.row);
    }
    std::printf("stage filter x %ld, route %d %s%s: checksum %.6g, route bytes per step %zu\n",
                repetitions, route_frames, NameOf(storage),
                WindowText(config.seqslam.filter).c_str(), checksum,
                ScanBytes(route_frames, dim, storage, config.seqslam.filter));
    return 0;
  }
  const MonotonicClock clock;
  Pipeline pipeline(clock);
  if (Status s = pipeline.Init(config); !s.ok())
    return Fail(s.message());
  std::vector<std::vector<std::uint8_t>> images;
  if (image_dir.empty() ? !RenderImages(&images) : !ReadImages(image_dir, &images))
    return Fail("no frames: the street camera failed, or IMAGE_DIR holds no rendered frames");

  if (stage == "segmentation") {
    dsp::SkySegmenter segmenter;
    if (segmenter.Init(pipeline.lens(), {}) != dsp::SegmentationError::kOk)
      return Fail("segmenter Init");
    for (long r = 0; r < repetitions; ++r) {
      dsp::SegmentationResult result;
      (void)segmenter.Threshold(View(images[static_cast<std::size_t>(r % kImages)]), &result);
      checksum += result.threshold;
    }
  } else if (stage == "descriptor" || stage == "strip") {
    for (long r = 0; r < repetitions; ++r) {
      FrameResult result;
      if (!pipeline.Describe(View(images[static_cast<std::size_t>(r % kImages)]), &result).ok())
        return Fail("Describe");
      checksum += static_cast<double>(pipeline.descriptor()[1]);
    }
  } else if (heading_stage) {
    // Strips of two different frames of the street (a turned query would cost the same).
    std::vector<std::vector<float>> strips;
    for (int i = 0; i < 2; ++i) {
      FrameResult result;
      if (!pipeline.Describe(View(images[static_cast<std::size_t>(i)]), &result).ok())
        return Fail("Describe");
      strips.emplace_back(pipeline.strip().begin(), pipeline.strip().end());
    }
    dsp::HeadingEstimator heading;
    if (heading.Init(config.heading.strip.n_azimuth, config.heading.estimate) !=
        dsp::HeadingError::kOk)
      return Fail("heading Init");
    const bool swap = stage == "heading_surf";
    for (long r = 0; r < repetitions; ++r) {
      const std::size_t stored = swap ? static_cast<std::size_t>(r % 2) : 0;
      dsp::HeadingEstimate estimate;
      (void)heading.Estimate(strips[stored], strips[1 - stored], &estimate);
      checksum += estimate.correlation_deg + estimate.surf_inliers;
    }
  } else if (stage == "frame") {
    // The route: the street's frames' descriptors and strips, each copy offset a little so
    // no two are equal (as frame_latency_bench builds it).
    RouteFrames route;
    if (!route
             .Allocate(static_cast<std::size_t>(route_frames),
                       static_cast<std::size_t>(pipeline.dim()), pipeline.strip_settings().columns)
             .ok())
      return Fail("route Allocate");
    std::vector<std::vector<float>> descriptors;
    std::vector<std::vector<std::uint8_t>> strips;
    for (const std::vector<std::uint8_t>& image : images) {
      FrameResult result;
      if (!pipeline.Describe(View(image), &result).ok())
        return Fail("Describe");
      descriptors.emplace_back(pipeline.descriptor().begin(), pipeline.descriptor().end());
      strips.emplace_back(pipeline.strip().begin(), pipeline.strip().end());
    }
    for (int i = 0; i < route_frames; ++i) {
      std::vector<float> d = descriptors[static_cast<std::size_t>(i % kImages)];
      for (float& v : d)
        v += 1e-4f * static_cast<float>(i / kImages);
      if (!route.Append({}, d, strips[static_cast<std::size_t>(i % kImages)]))
        return Fail("route Append");
    }
    if (!pipeline.SetRoute(route).ok() || pipeline.heading_enabled() != with_heading)
      return Fail("SetRoute");
    std::uint64_t frames_with_heading = 0;
    for (long r = 0; r < repetitions; ++r) {
      drivers::Frame frame;
      frame.image = View(images[static_cast<std::size_t>(r % kImages)]);
      frame.sequence = static_cast<std::uint64_t>(r);
      FrameResult result;
      if (!pipeline.Localise(frame, &result).ok())
        return Fail("Localise");
      frames_with_heading += result.has_heading ? 1 : 0;
      checksum += static_cast<double>(result.confidence);
    }
    std::printf("frames with heading: %llu of %ld\n",
                static_cast<unsigned long long>(frames_with_heading), repetitions);
  } else {
    return Fail("unknown STAGE");
  }
  std::printf("stage %s x %ld, route %d %s%s: checksum %.6g, route bytes per step %zu\n",
              stage.c_str(), repetitions, route_frames, NameOf(storage),
              WindowText(config.seqslam.filter).c_str(), checksum,
              stage == "frame"
                  ? ScanBytes(route_frames, pipeline.dim(), storage, config.seqslam.filter)
                  : 0);
  return 0;
}
