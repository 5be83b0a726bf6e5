#include "tools/eval_describe.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>

#include "firmware/descriptor.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/seqslam_batch.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/dsp/vanilla_descriptor.h"
#include "tools/parallel.h"
#include "tools/progress.h"

namespace skyloc::tools {

using drivers::DspStatus;

namespace {

// The lens: the camera file, else the dataset's camera.toml, else describe's default for a
// square-ish image (equidistant, 185 degrees); the lens model and field of view override
// any of them.
Status LensOfDataset(const drivers::DatasetCamera& camera, const std::string& dir,
                     const DescribeSettings& s, dsp::Lens* lens) {
  dsp::LensParams lp;
  std::string source = "default lens (equidistant 185 degrees)";
  const std::string& file = !s.camera.empty() ? s.camera : camera.dataset().camera_toml;
  if (!file.empty()) {
    SKYLOC_TRY_ASSIGN(lp, drivers::LoadCameraFile(file.c_str()));
    source = file;
    if (lp.width != camera.info().width || lp.height != camera.info().height) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "dataset %s has %dx%d frames but camera file %s describes %dx%d: "
                           "pass the camera file made for this camera with --camera",
                           dir.c_str(), camera.info().width, camera.info().height, file.c_str(),
                           lp.width, lp.height);
    }
  } else if (Result<dsp::LensParams> guess = drivers::GuessLensForImage(
                 camera.info().width, camera.info().height, camera.dataset().FramePath(0).c_str());
             guess.ok()) {
    lp = *guess;  // as `skyloc describe` guesses from the image's shape
    if (lp.model == dsp::LensModel::kEquirectangular)
      source = "default lens (equirectangular: a 2:1 image)";
  } else if (!s.lens) {
    return Status::Error(StatusCode::kInvalidArgument, "%s or --lens", guess.status().message());
  } else {
    lp.width = camera.info().width;  // --lens says what the shape could not
    lp.height = camera.info().height;
  }
  if (s.lens)
    lp.model = *s.lens;
  if (s.fov_deg)
    lp.fov_deg = *s.fov_deg;
  return drivers::InitLens(lp, source.c_str(), lens);
}

// The firmware's descriptor ([descriptor] of the configuration, else the built-in
// defaults), as the robot computes it; --bands has already replaced the bands.
// What describing one frame needs: the engines (one sky descriptor per worker, it holds
// scratch) and each worker's scratch rows.
struct Describer {
  ScoredDescriptor descriptor = ScoredDescriptor::kSky;
  const drivers::Dataset* dataset = nullptr;
  drivers::CameraInfo info;
  const DescribeSettings* settings = nullptr;
  std::vector<std::unique_ptr<dsp::SkyDescriptor>> skies;
  dsp::HorizonStrip horizon;
  std::vector<std::vector<float>> rows, strip_rows;

  Status Describe(std::size_t i, int worker, RunDescription* d);
};

Status Describer::Describe(std::size_t i, int worker, RunDescription* d) {
  const auto w = static_cast<std::size_t>(worker);
  const auto dim = static_cast<std::size_t>(d->dim);
  SKYLOC_TRY_ASSIGN(const drivers::OwnedImage image,
                    drivers::LoadImage(dataset->FramePath(i).c_str()));
  if (image.width() != info.width || image.height() != info.height ||
      image.format() != info.format) {
    return Status::Error(StatusCode::kDataLoss,
                         "dataset %s: frame %zu (%s) is %dx%d %s but the first frame is %dx%d %s",
                         dataset->dir.c_str(), i, dataset->frames[i].file.c_str(), image.width(),
                         image.height(), dsp::PixelFormatName(image.format()), info.width,
                         info.height, dsp::PixelFormatName(info.format));
  }
  const std::span<float> out = settings->floats ? std::span<float>(d->values.data() + i * dim, dim)
                                                : std::span<float>(rows[w]);
  if (descriptor == ScoredDescriptor::kSky) {
    const std::optional<dsp::Attitude>& attitude = dataset->frames[i].attitude;
    if (settings->attitude_from_dataset && !attitude) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s has no roll and pitch recorded (frames.csv): --attitude dataset "
                           "needs the attitude or pose columns (docs/DATASETS.md), or drop it",
                           dataset->FramePath(i).c_str());
    }
    const dsp::DescriptorError de = skies[w]->Compute(
        image.view(), out, nullptr, settings->attitude_from_dataset ? &*attitude : nullptr);
    if (!de.ok())
      return DspStatus(de, "%s: sky descriptor", dataset->FramePath(i).c_str());
    const auto columns = static_cast<std::size_t>(d->strip_columns);
    if (columns > 0) {
      std::vector<float>& strip = strip_rows[w];
      if (const dsp::HorizonStripError e = horizon.Extract(image.view(), strip);
          e != dsp::HorizonStripError::kOk)
        return DspStatus(e, "%s: horizon strip", dataset->FramePath(i).c_str());
      if (const dsp::HorizonStripError e = dsp::StripToBytes(
              strip, std::span<std::uint8_t>(d->strips).subspan(i * columns, columns));
          e != dsp::HorizonStripError::kOk)
        return DspStatus(e, "%s: horizon strip bytes", dataset->FramePath(i).c_str());
    }
  } else if (const dsp::VanillaError ve = dsp::VanillaDescriptor(image.view(), out);
             ve != dsp::VanillaError::kOk) {
    return DspStatus(ve, "%s", dataset->FramePath(i).c_str());
  }
  if (settings->bytes)
    dsp::QuantiseToBytes(out, std::span<std::uint8_t>(d->bytes.data() + i * dim, dim));
  return Status::Ok();
}

// Every frame on `workers` threads; the first frame (in order) that failed is the error.
Status DescribeFrames(Describer& describer, int workers, const std::string& label,
                      RunDescription* d) {
  const std::size_t n = describer.dataset->frames.size();
  std::mutex failure_mutex;
  std::size_t failed_at = n;
  Status failure;
  std::atomic<long> described{0};
  Progress progress(label, "frames", static_cast<long>(n));
  ParallelFor(workers, static_cast<int>(n), [&](int task, int worker) {
    const auto i = static_cast<std::size_t>(task);
    {
      const std::lock_guard<std::mutex> lock(failure_mutex);
      if (failed_at < i)
        return;  // an earlier frame failed: that is the error to report
    }
    const Status s = describer.Describe(i, worker, d);
    if (!s.ok()) {
      const std::lock_guard<std::mutex> lock(failure_mutex);
      if (i < failed_at) {
        failed_at = i;
        failure = s;
      }
    }
    const long done = described.fetch_add(1) + 1;
    if (worker == 0)
      progress.Update(done);
  });
  SKYLOC_TRY(failure);
  progress.Finish();
  return Status::Ok();
}

}  // namespace

dsp::SkyDescriptorOptions EvalSkyDescriptorOptions(const DescribeSettings& settings,
                                                   const dsp::Lens& lens) {
  firmware::Config config = settings.config;
  if (settings.max_tilt_deg)
    config.attitude.max_tilt_deg = *settings.max_tilt_deg;
  return firmware::SkyDescriptorOptionsFrom(config, lens, settings.attitude_from_dataset);
}

Result<RunDescription> DescribeDataset(ScoredDescriptor descriptor, const std::string& dir,
                                       const DescribeSettings& settings) {
  drivers::DatasetCamera camera(dir);
  SKYLOC_TRY(camera.Open());
  SKYLOC_TRY(camera.Start());
  RunDescription d;
  Describer describer;
  describer.descriptor = descriptor;
  describer.dataset = &camera.dataset();
  describer.info = camera.info();
  describer.settings = &settings;
  dsp::Lens lens_of_run;
  dsp::SkyDescriptorOptions options_of_run;
  const bool sky = descriptor == ScoredDescriptor::kSky;
  if (sky) {
    SKYLOC_TRY(LensOfDataset(camera, dir, settings, &lens_of_run));
    options_of_run = EvalSkyDescriptorOptions(settings, lens_of_run);
    d.dim = options_of_run.bands;
  } else {
    d.dim = dsp::kVanillaDescriptorSize;
  }
  // The firmware's horizon strip, for the heading of the correctly matched frames.
  const std::optional<dsp::HorizonStripOptions> strip_options =
      firmware::StripOptionsFrom(settings.config);
  if (sky && strip_options) {
    if (const dsp::HorizonStripError e = describer.horizon.Init(lens_of_run, *strip_options);
        e == dsp::HorizonStripError::kOk)
      d.strip_columns = strip_options->n_azimuth;
    else
      std::fprintf(stderr, "skyloc eval: %s: no heading: %s\n", dir.c_str(),
                   drivers::DspErrorMessage(e));
  }
  const std::size_t n = camera.dataset().frames.size();
  const auto dim = static_cast<std::size_t>(d.dim);
  const auto strip_columns = static_cast<std::size_t>(d.strip_columns);
  // Only the forms some run reads are kept: a bytes-only run holds a quarter of the
  // floats' memory (2 kB a vanilla frame instead of 8 kB).
  if (settings.floats)
    d.values.resize(n * dim);
  if (settings.bytes)
    d.bytes.resize(n * dim);
  d.strips.resize(n * strip_columns);
  const int workers = std::clamp(settings.jobs, 1, std::max(1, static_cast<int>(n)));
  describer.rows.assign(static_cast<std::size_t>(workers), std::vector<float>(dim));
  describer.strip_rows.assign(static_cast<std::size_t>(workers), std::vector<float>(strip_columns));
  for (int w = 0; sky && w < workers; ++w) {
    describer.skies.push_back(std::make_unique<dsp::SkyDescriptor>());
    if (const dsp::DescriptorError de = describer.skies.back()->Init(lens_of_run, options_of_run);
        !de.ok())
      return DspStatus(de, "sky descriptor for %s", dir.c_str());
  }
  SKYLOC_TRY(
      DescribeFrames(describer, workers,
                     std::string(ScoredDescriptorName(descriptor)) + " descriptors of " + dir, &d));
  d.count = static_cast<int>(n);
  camera.Close();
  return d;
}

}  // namespace skyloc::tools
