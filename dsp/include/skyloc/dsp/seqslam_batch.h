// The batch SeqSLAM engine at dataset scale: a cache-blocked difference matrix,
// an optional 8-bit descriptor, and a run that computes and consumes the matrix by blocks
// of query columns, so it needs N x (block + ds) floats instead of N x M.
//
// dsp/ has no threads: BlockedSeqSlam exposes the work of each block as independent
// ranges (columns to compute, query frames to search) that a caller may run on several
// threads (app/src/parallel.h does). Every float is computed by the same operations in
// the same order whatever the block size, the ranges or the thread that runs them, so the
// result is bit for bit BatchSeqSlam's (tests/dsp/seqslam_batch_test.cpp,
// tests/app/parallel_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/seqslam.h"

namespace skyloc::dsp {

// ---- 8-bit descriptors -----------------------------------------------------------------

// A byte descriptor stores round(x * kByteDescriptorScale) + 128, clamped to 0..255: steps
// of 1/16. Made for the vanilla descriptor, whose values are z-scores within 8x8 patches
// and so lie in +-(64 - 1)/sqrt(64) = +-7.875 (Samuelson): x 16 is +-126, nothing clips.
// The difference of two byte rows is their integer sum of absolute differences (exact, in
// any order: SSE2 psadbw on x86-64, NEON uabal on aarch64, plain code elsewhere), reported
// as sum / (16 x dim): the mean absolute difference in the float descriptor's units.
inline constexpr float kByteDescriptorScale = 16.0f;

void QuantiseToBytes(std::span<const float> values, std::span<std::uint8_t> out);

// Descriptors row by row, as floats or as bytes (made by Floats() or Bytes(); the other
// span stays empty).
struct DescriptorRows {
  std::span<const float> floats;
  std::span<const std::uint8_t> bytes;
  int dim = 0;
  bool byte_rows = false;

  bool is_bytes() const { return byte_rows; }
  int count() const {
    const std::size_t n = is_bytes() ? bytes.size() : floats.size();
    return dim > 0 ? static_cast<int>(n / static_cast<std::size_t>(dim)) : 0;
  }
  static DescriptorRows Floats(std::span<const float> v, int dim) { return {v, {}, dim, false}; }
  static DescriptorRows Bytes(std::span<const std::uint8_t> v, int dim) {
    return {{}, v, dim, true};
  }
};

// The difference tile of reference rows [r0, r1) against query rows [q0, q1):
// out[(q - q0) * out_stride + (r - r0)]. Both sets must be floats, or both bytes. For
// floats every entry is bit for bit DifferenceColumn's (the same eight partial sums per
// pair, added in the same order); the tile only changes which pairs share a load. Two
// references x two queries (floats) or x four queries (bytes) per pass; references in
// 16 KiB tiles that stay in L1 while every query of [q0, q1) passes over them.
void DifferenceTile(const DescriptorRows& reference, const DescriptorRows& query, int r0, int r1,
                    int q0, int q1, float* out, std::size_t out_stride);

// ---- The blocked batch engine ----------------------------------------------------------

struct BlockedSeqSlamOptions {
  // Query frames matched per block. The engine holds the enhanced columns of one block
  // plus ds - 1: n_ref x (block + ds - 1) floats. The result does not depend on it.
  int block_columns = 256;
};

// One run over a block of query frames:
//   Begin(b) -> ColumnCount() columns to compute: ComputeColumns over disjoint ranges of
//   0..ColumnCount() (any order, any threads; each call needs a scratch of
//   ScratchFloats() floats) -> SearchCount() query frames: Search over disjoint
//   ranges of 0..SearchCount() (each needs ScoreFloats() floats of scratch).
// Run() does all of it on the calling thread.
class BlockedSeqSlam {
 public:
  // Checks the sizes and the parameters and allocates the column store. `matches` is
  // written by Search (n_query entries; frames without a full window get valid = false).
  SeqSlamError Init(const DescriptorRows& reference, const DescriptorRows& query,
                    const SeqSlamParams& params, SeqSlamWindow window,
                    const BlockedSeqSlamOptions& options, std::span<SeqSlamMatch> matches);

  int block_count() const { return block_count_; }
  int block_columns() const { return block_; }
  // Prepares block b (blocks in increasing order): keeps the enhanced columns the block
  // shares with the previous one, lists the ones it still needs.
  void Begin(int block);
  int ColumnCount() const { return new_end_ - new_begin_; }
  // Query columns [begin, end) of 0..ColumnCount(): differences (DifferenceTile) and
  // contrast enhancement (EnhanceColumn) into the column store.
  void ComputeColumns(int begin, int end, std::span<float> scratch);
  // Columns ComputeColumns handles per pass over the references: ranges of this many
  // columns balance threads best.
  static constexpr int kColumnGroup = 32;
  std::size_t ScratchFloats() const;
  int SearchCount() const { return t_end_ - t_begin_; }
  // Query frames [begin, end) of 0..SearchCount(): the trajectory search.
  void Search(int begin, int end, std::span<float> scores);
  std::size_t ScoreFloats() const { return static_cast<std::size_t>(n_ref_); }

  // Everything on the calling thread.
  void Run();

  int n_ref() const { return n_ref_; }
  int n_query() const { return n_query_; }
  // Bytes of the column store (the run's memory beyond the descriptors and the scratch).
  std::size_t AllocatedBytes() const { return sizeof(float) * store_.size(); }

 private:
  float* Column(int q);
  // The query columns [first, last) frame t's window reads (first > last: none).
  void WindowOf(int t, int* first, int* last) const;

  DescriptorRows reference_, query_;
  SeqSlamParams params_;
  SeqSlamWindow window_ = SeqSlamWindow::kCentred;
  TrajectorySearch search_;
  std::span<SeqSlamMatch> matches_;
  int n_ref_ = 0, n_query_ = 0;
  int block_ = 0, block_count_ = 0;
  int slots_ = 0;  // columns the store holds: block + ds - 1
  int t_begin_ = 0, t_end_ = 0;
  int have_begin_ = 0, have_end_ = 0;  // enhanced columns in the store
  int new_begin_ = 0, new_end_ = 0;    // columns Begin() asked for
  // Column q lives in slot q % slots_: a block's columns are contiguous in q, so no two
  // columns the block needs share a slot.
  std::vector<float> store_;
};

// BatchSeqSlam through BlockedSeqSlam on one thread: the same matches, bit for bit, in
// n_ref x (block + ds - 1) floats.
SeqSlamError BlockedBatchSeqSlam(const DescriptorRows& reference, const DescriptorRows& query,
                                 const SeqSlamParams& params, SeqSlamWindow window,
                                 const BlockedSeqSlamOptions& options,
                                 std::span<SeqSlamMatch> matches);

}  // namespace skyloc::dsp
