#include "tools/features.h"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "skyloc/drivers/dataset.h"

namespace skyloc::tools {
namespace {

Status FromException(const char* what, const char* doing) {
  return Status::Error(StatusCode::kInternal, "OpenCV failed while %s: %s", doing, what);
}

// A grey cv::Mat of the view (a copy for colour formats, a wrapper for grey).
cv::Mat ToGrey(const dsp::ImageView& image) {
  auto* data = const_cast<std::uint8_t*>(image.data);  // NOLINT: OpenCV wants non-const
  switch (image.format) {
    case dsp::PixelFormat::kGrey8:
      return cv::Mat(image.height, image.width, CV_8UC1, data, image.stride);
    case dsp::PixelFormat::kRgb24: {
      cv::Mat grey;
      cv::cvtColor(cv::Mat(image.height, image.width, CV_8UC3, data, image.stride), grey,
                   cv::COLOR_RGB2GRAY);
      return grey;
    }
    case dsp::PixelFormat::kBgr24: {
      cv::Mat grey;
      cv::cvtColor(cv::Mat(image.height, image.width, CV_8UC3, data, image.stride), grey,
                   cv::COLOR_BGR2GRAY);
      return grey;
    }
    case dsp::PixelFormat::kYuyv: {
      cv::Mat grey;
      cv::cvtColor(cv::Mat(image.height, image.width, CV_8UC2, data, image.stride), grey,
                   cv::COLOR_YUV2GRAY_YUYV);
      return grey;
    }
  }
  return {};
}

}  // namespace

Status ExtractSift(const dsp::ImageView& image, const FeatureSettings& settings,
                   std::vector<float>* out) {
  if (image.empty())
    return Status::Error(StatusCode::kInvalidArgument, "SIFT: empty image");
  try {
    cv::Mat small;
    cv::resize(ToGrey(image), small, cv::Size(settings.width, settings.height), 0, 0,
               cv::INTER_AREA);
    cv::Ptr<cv::SIFT> sift = cv::SIFT::create(settings.max_features);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat desc;
    sift->detectAndCompute(small, cv::noArray(), keypoints, desc);
    if (desc.empty())
      return Status::Ok();
    if (desc.type() != CV_32F || desc.cols != kSiftDim)
      return Status::Error(StatusCode::kInternal, "SIFT returned %dx%d of type %d", desc.rows,
                           desc.cols, desc.type());
    // OpenCV may return a few more than nfeatures (ties at the response cut-off).
    const int rows = std::min(desc.rows, settings.max_features);
    for (int r = 0; r < rows; ++r) {
      const float* row = desc.ptr<float>(r);
      out->insert(out->end(), row, row + kSiftDim);
    }
  } catch (const std::exception& e) {
    return FromException(e.what(), "extracting SIFT features");
  }
  return Status::Ok();
}

Status ClusterWords(std::span<const float> descriptors, int dim, int words, std::uint64_t seed,
                    std::vector<float>* centres) {
  const auto rows = static_cast<int>(descriptors.size() / static_cast<std::size_t>(dim));
  if (words < 2 || rows < words) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "cannot cluster %d descriptors into %d words: train on more images or "
                         "ask for fewer words (--words)",
                         rows, words);
  }
  try {
    // cv::Mat over our buffer; kmeans only reads it.
    const cv::Mat data(rows, dim, CV_32F, const_cast<float*>(descriptors.data()));  // NOLINT
    cv::Mat labels, c;
    cv::theRNG().state = seed == 0 ? 1 : seed;
    cv::kmeans(data, words, labels,
               cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 1e-3), 1,
               cv::KMEANS_PP_CENTERS, c);
    centres->assign(c.ptr<float>(0), c.ptr<float>(0) + static_cast<std::size_t>(words) *
                                                           static_cast<std::size_t>(dim));
  } catch (const std::exception& e) {
    return FromException(e.what(), "clustering the vocabulary (k-means++)");
  }
  return Status::Ok();
}

Status Quantise(std::span<const float> descriptors, std::span<const float> centres, int dim,
                WordList* out) {
  out->clear();
  const auto d = static_cast<std::size_t>(dim);
  const std::size_t rows = descriptors.size() / d, words = centres.size() / d;
  if (rows == 0)
    return Status::Ok();
  try {
    const cv::Mat query(static_cast<int>(rows), dim, CV_32F,
                        const_cast<float*>(descriptors.data()));  // NOLINT
    const cv::Mat train(static_cast<int>(words), dim, CV_32F,
                        const_cast<float*>(centres.data()));  // NOLINT
    cv::BFMatcher matcher(cv::NORM_L2);
    std::vector<cv::DMatch> matches;
    matcher.match(query, train, matches);
    for (const cv::DMatch& m : matches)
      out->push_back(static_cast<std::uint32_t>(m.trainIdx));
  } catch (const std::exception& e) {
    return FromException(e.what(), "assigning features to words");
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
  return Status::Ok();
}

Status ImageWords(const dsp::ImageView& image, const Vocabulary& vocabulary,
                  std::vector<float>* descriptors, WordList* out) {
  descriptors->clear();
  SKYLOC_TRY(ExtractSift(image, vocabulary.features, descriptors));
  return Quantise(*descriptors, vocabulary.centres, vocabulary.features.descriptor_dim, out);
}

namespace {

// Calls fn(index, descriptors) for every frame of the dataset.
template <typename Fn>
Status ForEachFrameFeatures(const std::string& dir, const FeatureSettings& settings, Fn fn) {
  drivers::DatasetCamera camera(dir);
  SKYLOC_TRY(camera.Open());
  SKYLOC_TRY(camera.Start());
  const std::size_t n = camera.dataset().frames.size();
  std::vector<float> desc;
  for (std::size_t i = 0; i < n; ++i) {
    Result<drivers::Frame> frame = camera.Capture(Nanoseconds(0));
    if (!frame.ok())
      return frame.status();
    desc.clear();
    if (Status s = ExtractSift(frame->image, settings, &desc); !s.ok())
      return s.AddContext("%s", camera.dataset().FramePath(i).c_str());
    SKYLOC_TRY(fn(i, desc));
  }
  camera.Close();
  return Status::Ok();
}

}  // namespace

Result<std::vector<WordList>> DatasetWords(const std::string& dir, const Vocabulary& v) {
  std::vector<WordList> lists;
  const auto add = [&](std::size_t, const std::vector<float>& d) {
    WordList w;
    const Status s = Quantise(d, v.centres, v.features.descriptor_dim, &w);
    lists.push_back(std::move(w));
    return s;
  };
  SKYLOC_TRY(ForEachFrameFeatures(dir, v.features, add));
  return lists;
}

Result<Vocabulary> TrainVocabulary(const TrainOptions& o) {
  if (o.datasets.empty())
    return Status::Error(StatusCode::kInvalidArgument, "no training datasets: give --train DIR");
  Vocabulary v;
  v.features = o.features;
  v.words = o.words;
  // 1. Features of every training frame, kept per frame for step 3.
  std::vector<std::vector<float>> frames;
  std::size_t total = 0;
  for (const std::string& dir : o.datasets) {
    std::fprintf(stderr, "skyloc fabmap-train: SIFT features of %s...\n", dir.c_str());
    const auto keep_frame = [&](std::size_t, const std::vector<float>& d) {
      frames.push_back(d);
      total += d.size() / kSiftDim;
      return Status::Ok();
    };
    SKYLOC_TRY(ForEachFrameFeatures(dir, v.features, keep_frame));
  }
  // 2. The vocabulary: k-means++ over an even subsample of all descriptors.
  const std::size_t keep = std::min<std::size_t>(
      total, static_cast<std::size_t>(std::max(1, o.max_cluster_descriptors)));
  std::vector<float> pool;
  pool.reserve(keep * kSiftDim);
  std::size_t index = 0, taken = 0;
  for (const std::vector<float>& f : frames) {
    for (std::size_t r = 0; r < f.size() / kSiftDim; ++r, ++index) {
      // Row `index` is kept when it crosses the next multiple of total / keep.
      if (taken < keep && (index * keep) / total == taken) {
        pool.insert(pool.end(), f.begin() + static_cast<std::ptrdiff_t>(r * kSiftDim),
                    f.begin() + static_cast<std::ptrdiff_t>((r + 1) * kSiftDim));
        ++taken;
      }
    }
  }
  std::fprintf(stderr,
               "skyloc fabmap-train: %zu frames, %zu descriptors; k-means++ of %zu into %d "
               "words...\n",
               frames.size(), total, taken, o.words);
  SKYLOC_TRY(ClusterWords(pool, kSiftDim, o.words, o.seed, &v.centres));
  // 3. Each training frame's words; the Chow-Liu tree of their occurrences.
  std::vector<WordList> lists(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i)
    SKYLOC_TRY(Quantise(frames[i], v.centres, kSiftDim, &lists[i]));
  std::fprintf(stderr, "skyloc fabmap-train: Chow-Liu tree of %d words over %zu frames...\n",
               o.words, lists.size());
  SKYLOC_TRY_ASSIGN(v.tree, LearnChowLiuTree(lists, o.words));
  // 4. The new-place samples: evenly spaced training frames, at most max_samples.
  const std::size_t ns =
      std::min(lists.size(), static_cast<std::size_t>(std::max(1, o.max_samples)));
  for (std::size_t k = 0; k < ns; ++k)
    v.samples.push_back(lists[k * lists.size() / ns]);
  SKYLOC_TRY(CheckVocabulary(v));
  return v;
}

}  // namespace skyloc::tools
