// `skyloc fabmap-train`: the FAB-MAP 2.0 vocabulary from separate training runs (SIFT
// features, k-means++ words, Chow-Liu tree, new-place samples), for `skyloc eval --method
// fabmap` (docs/FABMAP.md). Host builds only: cross builds leave OpenCV out.
#include <charconv>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>

#include "cli/commands.h"
#include "skyloc/platform/status.h"
#include "tools/features.h"
#include "tools/vocabulary.h"

namespace skyloc::cli {
using namespace skyloc::tools;
namespace {

constexpr const char* kUsage =
    "usage: skyloc fabmap-train --train DIR [--train DIR...] --out VOCAB [options]\n"
    "\n"
    "Trains the FAB-MAP 2.0 vocabulary on dataset folders (docs/DATASETS.md) that are NOT\n"
    "the runs you will evaluate (the paper trained on a separate video): SIFT features of\n"
    "every frame at 480x270, k-means++ words, the Chow-Liu tree of word occurrences and\n"
    "the new-place samples. Writes VOCAB (docs/FABMAP.md, \"Vocabulary file\").\n"
    "\n"
    "  --words N          vocabulary size (default 500; 2..20000)\n"
    "  --max-features N   strongest SIFT keypoints per frame (default 500)\n"
    "  --samples N        training frames kept for the new-place model (default 1000,\n"
    "                     OpenFABMAP's NumSamples)\n"
    "  --cluster-max N    descriptors k-means sees, evenly subsampled (default 40000)\n"
    "  --seed N           k-means++ seed (default 1)\n";

[[maybe_unused]] bool ParsePositive(const char* s, int* out) {
  const char* end = s + std::strlen(s);
  auto [p, ec] = std::from_chars(s, end, *out);
  return ec == std::errc() && p == end && end != s && *out > 0;
}

}  // namespace

int RunFabmapTrain(std::span<char* const> args) {
  auto fail = [](std::string_view what, const char* a) {
    return UsageError("fabmap-train", what, a);
  };
  tools::TrainOptions o;
  std::string out;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (IsHelpFlag(args[i])) {
      std::fputs(kUsage, stdout);
      return kExitOk;
    }
    if (i + 1 >= args.size())
      return fail("%s needs a value", args[i]);
    const char* v = args[++i];
    int n = 0;
    if (a == "--train") {
      o.datasets.emplace_back(v);
    } else if (a == "--out") {
      out = v;
    } else if (a == "--words") {
      if (!ParsePositive(v, &n) || n < 2 || n > 20000)
        return fail("--words '%s': give 2..20000", v);
      o.words = n;
    } else if (a == "--max-features") {
      if (!ParsePositive(v, &n) || n > 100000)
        return fail("--max-features '%s': give 1..100000", v);
      o.features.max_features = n;
    } else if (a == "--samples") {
      if (!ParsePositive(v, &n))
        return fail("--samples '%s': give a whole number > 0", v);
      o.max_samples = n;
    } else if (a == "--cluster-max") {
      if (!ParsePositive(v, &n))
        return fail("--cluster-max '%s': give a whole number > 0", v);
      o.max_cluster_descriptors = n;
    } else if (a == "--seed") {
      if (!ParsePositive(v, &n))
        return fail("--seed '%s': give a whole number > 0", v);
      o.seed = static_cast<std::uint64_t>(n);
    } else {
      return fail("unknown option '%s'", args[i - 1]);
    }
  }
  if (o.datasets.empty() || out.empty())
    return fail("%s", "--train DIR and --out VOCAB are required");
  Result<tools::Vocabulary> v = tools::TrainVocabulary(o);
  Status s = v.ok() ? tools::SaveVocabulary(out, *v) : v.status();
  if (!s.ok()) {
    std::fprintf(stderr, "skyloc fabmap-train: %s\n", s.message());
    return kExitFailure;
  }
  std::printf("skyloc fabmap-train: %d words, %zu new-place samples, written to %s\n", v->words,
              v->samples.size(), out.c_str());
  return kExitOk;
}

}  // namespace skyloc::cli
