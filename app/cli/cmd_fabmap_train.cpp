// `skyloc fabmap-train`: the FAB-MAP 2.0 vocabulary from separate training runs (SIFT
// features, k-means++ words, Chow-Liu tree, new-place samples), for `skyloc eval --method
// fabmap` (docs/FABMAP.md). Host builds only: cross builds leave OpenCV out.
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include "cli/commands.h"
#include "skyloc/platform/status.h"
#include "tools/features.h"
#include "tools/vocabulary.h"

namespace skyloc::cli {
using namespace skyloc::tools;
namespace {

constexpr const char* kDescription =
    "Trains the FAB-MAP 2.0 vocabulary on dataset folders (docs/DATASETS.md) that are NOT\n"
    "the runs you will evaluate (the paper trained on a separate video): SIFT features of\n"
    "every frame at 480x270, k-means++ words, the Chow-Liu tree of word occurrences and\n"
    "the new-place samples. Writes VOCAB (docs/FABMAP.md, \"Vocabulary file\").\n";

struct FabmapTrainOptions {
  tools::TrainOptions train;
  std::string out;
};

ParseOutcome ParseArgs(std::span<char* const> args, FabmapTrainOptions* options) {
  tools::TrainOptions& o = options->train;
  OptionTable t("fabmap-train", "--train DIR [--train DIR...] --out VOCAB [options]", kDescription);
  t.TextList("--train", "DIR", "a training dataset folder (repeat for more)", &o.datasets);
  t.Text("--out", "VOCAB", "the vocabulary file to write", &options->out);
  t.Int("--words", "N", "vocabulary size (default 500)", 2, 20000, &o.words);
  t.Int("--max-features", "N", "strongest SIFT keypoints per frame (default 500)", 1, 100000,
        &o.features.max_features);
  t.Int("--samples", "N",
        "training frames kept for the new-place model (default 1000, OpenFABMAP's NumSamples)", 1,
        std::numeric_limits<int>::max(), &o.max_samples);
  t.Int("--cluster-max", "N", "descriptors k-means sees, evenly subsampled (default 40000)", 1,
        std::numeric_limits<int>::max(), &o.max_cluster_descriptors);
  std::int64_t seed = static_cast<std::int64_t>(o.seed);
  t.Int("--seed", "N", "k-means++ seed (default 1)", 1, std::numeric_limits<int>::max(), &seed);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  o.seed = static_cast<std::uint64_t>(seed);
  if (o.datasets.empty() || options->out.empty())
    return t.Refuse("--train DIR and --out VOCAB are required");
  return ParseOutcome::kRun;
}

int TrainAndSave(const FabmapTrainOptions& options) {
  const tools::TrainOptions& o = options.train;
  const std::string& out = options.out;
  Result<tools::Vocabulary> v = tools::TrainVocabulary(o);
  Status s = v.ok() ? tools::SaveVocabulary(out, *v) : v.status();
  if (!s.ok())
    return Failed("fabmap-train", s);
  std::printf("skyloc fabmap-train: %d words, %zu new-place samples, written to %s\n", v->words,
              v->samples.size(), out.c_str());
  return kExitOk;
}

}  // namespace

int RunFabmapTrain(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, TrainAndSave);
}

}  // namespace skyloc::cli
