// SeqSLAM (Milford & Wyeth 2012) as OpenSeqSLAM (Suenderhauf 2013) implements it, over any
// descriptor vectors: a difference matrix D (reference rows x query columns, mean absolute
// difference), local contrast enhancement of each entry against its +-R/2 neighbouring
// reference rows, and a search for the straight trajectory through ds query columns, at
// velocities vmin..vmax reference frames per query frame, with the lowest summed
// enhanced difference. Two engines share every numerical step, so they agree bit for bit:
//
//  - the batch engine (offline, `skyloc eval`): whole matrices, centred window (as
//    OpenSeqSLAM) or trailing window (what the firmware can do);
//  - StreamingSeqSlam (the firmware): a fixed reference database and a ring of the last
//    ds enhanced difference columns; Step() is causal and allocates nothing.
//
// Storage convention: D is kept column by column (query-major): column q, the differences
// of query q to all N references, is contiguous (d[q * N + r]). That is the unit the
// streaming engine produces per frame and what the search reads sequentially.
//
// Deliberate differences from OpenSeqSLAM (MATLAB, openSeqSLAM.m / doFindMatches.m), each
// also noted where it happens in seqslam.cpp:
//  1. A trajectory covers ds query frames. OpenSeqSLAM rounds ds up to even and spans
//     ds + 1 columns (N - ds/2 .. N + ds/2); ds = 1 (single image) is then impossible.
//  2. The velocities are vmin, vmin + vstep, ... <= vmax. OpenSeqSLAM steps 1/ds (its
//     `vskip` is unused); with the defaults (ds = 10, step 0.1) both give 0.8..1.2.
//  3. D is divided by the descriptor length (mean absolute difference). OpenSeqSLAM
//     divides by the number of reference images; the scale cancels in the enhancement.
//  4. Enhanced values are shifted by the constant (m-1)/sqrt(m), m = min(N, 2*floor(R/2)+1):
//     the most negative z-score a window of m samples can produce, so every value is >= 0.
//     OpenSeqSLAM subtracts the global minimum of the enhanced matrix, which needs the
//     whole run (not causal). Every trajectory has the same length, so the shift changes
//     no ranking; the uniqueness ratio differs slightly.
//  5. A zero standard deviation (all neighbours equal) gives 0, not NaN.
//  6. The matched reference is the best trajectory's row at the query frame itself
//     (start + floor(v * position)), not start + ds/2 whatever the velocity.
//  7. Trajectories that leave the database are not candidates. OpenSeqSLAM appends a row
//     of +inf to reach the same effect; the C++ ports append it before the enhancement
//     (corrupting the last rows' statistics) and decode flat indices with wrap-around:
//     neither is done here.
//  8. With no runner-up outside the uniqueness window (a database shorter than the
//     window) the uniqueness is 1 ("not distinctive"); OpenSeqSLAM fails on an empty min.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace skyloc::dsp {

enum class SeqSlamError : std::uint8_t {
  kOk = 0,
  kBadSequenceLength,    // ds outside 1..kMaxSequenceLength
  kBadVelocity,          // vmin < 0, vmax < vmin, vmax > 8, vstep <= 0 or > kMaxVelocities steps
  kBadContrastWindow,    // R outside 0..kMaxWindow
  kBadUniquenessWindow,  // Rwindow outside 0..kMaxWindow
  kBadDimension,         // descriptor length < 1
  kBadCapacity,          // database capacity < 1
  kSizeMismatch,         // a span's size does not match the sizes given
  kDatabaseFull,         // AddReference beyond the capacity given to Init
  kNotInitialised,       // StreamingSeqSlam used before a successful Init
  kEmptyDatabase,        // Step() with no reference frames
  kBadMaxAdvance,        // route filter: max_advance outside 1..kMaxAdvance
  kBadKeyframeFactor,    // route filter: keyframe_noise_factor outside 0..100
  kRouteNotFinished,     // route filter: Step() before FinishRoute()
  kRouteFinished,        // route filter: AddReference() after FinishRoute()
  kBadSearchWindow,      // route filter: search_window outside 0..kMaxSearchWindow
  kBadRefreshFrames,     // route filter: refresh_frames outside 1..kMaxRefreshFrames with a
                         // search window, or not 0 without one
};

// A sentence saying what is wrong, for the caller to turn into its error.
const char* SeqSlamErrorMessage(SeqSlamError error);

inline constexpr int kMaxSequenceLength = 1000;
inline constexpr int kMaxVelocities = 64;
inline constexpr int kMaxWindow = 10000;

struct SeqSlamParams {
  int sequence_length = 10;  // ds: query frames in one trajectory (1 = single image)
  float v_min = 0.8f;        // reference frames per query frame
  float v_max = 1.2f;
  float v_step = 0.1f;
  int uniqueness_window = 10;  // Rwindow: starts within +-Rwindow/2 of the best are excluded
  int contrast_window = 10;    // R: enhancement uses the +-R/2 neighbouring reference rows

  bool operator==(const SeqSlamParams&) const = default;
};

SeqSlamError ValidateSeqSlamParams(const SeqSlamParams& params);

enum class SeqSlamWindow : std::uint8_t {
  kCentred,   // query frames t - ds/2 .. t - ds/2 + ds - 1 (OpenSeqSLAM; needs the future)
  kTrailing,  // query frames t - ds + 1 .. t (causal: the firmware's engine)
};

struct SeqSlamMatch {
  // False when the window does not fit in the query frames around t, or no trajectory
  // fits in the database; the other fields are then meaningless.
  bool valid = false;
  int reference = -1;  // the reference frame matched to query frame t
  // The engine's route row: the reference frame itself for SeqSLAM, a keyframe row for
  // the route filter (docs/SEQSLAM.md). Route-index consistency is checked in rows.
  int row = -1;
  int start = -1;      // the reference row where the best trajectory starts
  float velocity = 0;  // its velocity (reference frames per query frame)
  // Sum of the shifted enhanced differences along the trajectory (>= 0, lower = better).
  float score = 0;
  // score / lowest score of the starts outside +-Rwindow/2 of the best start: 0..1, lower
  // is more distinctive (OpenSeqSLAM's match quality; accept when below a threshold).
  float uniqueness = 1;
  // 1 - uniqueness: 0 = no better than the runner-up elsewhere on the route, 1 = the
  // runner-up is infinitely worse. See docs/SEQSLAM.md.
  float confidence = 0;
};

// ---- Building blocks (shared by both engines) -----------------------------------------

// out[r] = mean over d of |database[r * dim + d] - query[d]|, for the N = out.size()
// references stored row by row in `database`.
void DifferenceColumn(std::span<const float> database, int dim, std::span<const float> query,
                      std::span<float> out);

// The same over a database stored as bfloat16 (ReferenceStorage::kBFloat16). Bit for bit
// equal to DifferenceColumn over the database converted back with FromBFloat16.
void DifferenceColumnBFloat16(std::span<const std::uint16_t> database, int dim,
                              std::span<const float> query, std::span<float> out);

// bfloat16: the upper 16 bits of an IEEE float (8 significant bits, the float's range).
// ToBFloat16 rounds to nearest, ties to even; FromBFloat16 is exact.
std::uint16_t ToBFloat16(float value);
float FromBFloat16(std::uint16_t value);

// A descriptor row as unsigned integer codes with one power-of-two scale 2^e for the row
// (ReferenceStorage::kCodes8, kCodes16). The exponent e is the smallest that fits the
// row's largest value in the codes.
//  - 16 bits, linear: value = code * 2^e, code = round(v / 2^e); the largest value's code
//    is 32768..65535, and |v - code 2^e| <= 2^(e-1) < max(row) / 65535.
//  - 8 bits, square law: value = code^2 * 2^e, code = round(sqrt(v / 2^e)); the largest
//    value's code is 181..255 and 2^e <= max(row) / 32640, so
//    |v - code^2 2^e| <= (sqrt(v / 2^e) + 1/4) 2^e: about max / 181 at the largest value
//    and sqrt(v max / 32640) below it, a relative error that grows only as 1/sqrt(v)
//    where a linear 8-bit code's grows as 1/v. Amplitude spectra hold a few large and many
//    small values, and the small ones (fine detail) are what tells similar places apart.
// A power of two (and code^2 <= 65025 < 2^24) makes the decoded value exact in float (no
// rounding on any machine) and the encoding idempotent: a decoded row encodes to the same
// codes and exponent, so a route read back from its file and stored again is bit for bit
// the same.
// Amplitude spectra are >= 0: a negative or NaN value is stored as code 0. The exponent
// stays in kCodeMinExponent..kCodeMaxExponent, so every decoded value is a normal float or
// zero (a row whose largest value is below 2^-110 has codes of 0 and small integers).
inline constexpr int kCodeMinExponent = -118;
inline constexpr int kCodeMaxExponent = 100;
// The scale 2^e of a code row, exact for kCodeMinExponent..kCodeMaxExponent (normal floats).
inline float CodeScale(int exponent) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(exponent + 127) << 23);
}
template <typename Code>
std::int8_t EncodeCodes(std::span<const float> row, std::span<Code> codes);
template <typename Code>
void DecodeCodes(std::span<const Code> codes, std::int8_t exponent, std::span<float> out);
extern template std::int8_t EncodeCodes(std::span<const float>, std::span<std::uint8_t>);
extern template std::int8_t EncodeCodes(std::span<const float>, std::span<std::uint16_t>);
extern template void DecodeCodes(std::span<const std::uint8_t>, std::int8_t, std::span<float>);
extern template void DecodeCodes(std::span<const std::uint16_t>, std::int8_t, std::span<float>);

// DifferenceColumn over a database of code rows (row r: codes[r * dim ..], exponents[r]).
// Bit for bit equal to DifferenceColumn over the rows decoded with DecodeCodes.
template <typename Code>
void DifferenceColumnCodes(std::span<const Code> codes, std::span<const std::int8_t> exponents,
                           int dim, std::span<const float> query, std::span<float> out);
extern template void DifferenceColumnCodes(std::span<const std::uint8_t>,
                                           std::span<const std::int8_t>, int,
                                           std::span<const float>, std::span<float>);
extern template void DifferenceColumnCodes(std::span<const std::uint16_t>,
                                           std::span<const std::int8_t>, int,
                                           std::span<const float>, std::span<float>);

// Local contrast enhancement of one column of D: out[r] = (d[r] - mean) / std over rows
// max(0, r - R/2) .. min(N - 1, r + R/2) (sample std, as MATLAB's std), plus the shift of
// note 4 above; 0 + shift where the std is 0. O(N) with running sums.
void EnhanceColumn(std::span<const float> d, int contrast_window, std::span<float> out);

// The constant added by EnhanceColumn for a database of n references (note 4).
float EnhancementShift(int n, int contrast_window);

// EnhanceColumn produced incrementally, as the rows of d arrive: the streaming engine
// enhances the rows of a column while the rest of its differences are still being read
// from the database. Every row gets the same operations in the same order however the
// column is split, so the result equals EnhanceColumn's bit for bit (EnhanceColumn is
// Begin + one Advance). Holds a fixed scratch of kRowsPerPass floats: allocates nothing.
class ColumnEnhancer {
 public:
  void Begin(int n, int contrast_window);
  // d[0 .. available) are known (available <= n). Writes out[r] for every row whose
  // window is complete and returns how many leading rows of out are final.
  int Advance(const float* d, int available, float* out);

 private:
  static constexpr int kRowsPerPass = 256;
  int n_ = 0;
  int half_ = 0;
  float shift_ = 0;
  int done_ = 0;  // rows of out written
  int m_ = 0;     // rows in the running window of row done_
  bool primed_ = false;
  double sum_ = 0, sum_sq_ = 0;  // running sums over the window of row done_
  float mean_[kRowsPerPass];
  float var_[kRowsPerPass];
};

// The trajectory search over a window of ds enhanced columns.
class TrajectorySearch {
 public:
  // Allocates the velocity offset table (start-up only).
  SeqSlamError Init(const SeqSlamParams& params);

  // columns: ds pointers to enhanced columns of n floats, oldest query frame first.
  // position: which of the ds query frames the match is reported for (0..ds-1).
  // scores: scratch of >= n floats; on return scores[s] is the best trajectory score
  // starting at reference row s (+inf when no velocity fits). Allocates nothing.
  // Search = ScoreStarts over 0..n, then Finish.
  SeqSlamMatch Search(std::span<const float* const> columns, int n, int position,
                      std::span<float> scores) const;

  // scores[s] for starts s in [begin, end): reads rows s .. s + max_offset() of the
  // columns. Each score is summed in the same order whatever the range, so scoring a
  // database piece by piece gives the same floats as scoring it at once.
  void ScoreStarts(std::span<const float* const> columns, int n, int begin, int end,
                   std::span<float> scores) const;
  // The match from complete scores: best start, its velocity, the runner-up.
  SeqSlamMatch Finish(std::span<const float* const> columns, int n, int position,
                      std::span<const float> scores) const;

  int sequence_length() const { return sequence_length_; }
  int velocity_count() const { return velocity_count_; }
  float velocity(int k) const { return velocities_[static_cast<std::size_t>(k)]; }
  // floor(j * v_k): reference rows advanced after j query frames at velocity k.
  int offset(int k, int j) const {
    return offsets_[static_cast<std::size_t>(k * sequence_length_ + j)];
  }
  // The largest offset(k, ds - 1): a trajectory from start s reads rows up to s + this.
  int max_offset() const { return max_offset_; }

 private:
  int sequence_length_ = 0;
  int velocity_count_ = 0;
  int uniqueness_window_ = 0;
  int max_offset_ = 0;
  std::vector<float> velocities_;
  std::vector<int> offsets_;  // velocity_count_ x sequence_length_
  // The velocities whose row offsets differ from every earlier velocity's: with ds = 10,
  // 1.0 and 1.1 give the same rows (floor(9 * 1.1) = 9), so one sum serves both.
  std::vector<int> distinct_;
};

// ---- Batch engine ----------------------------------------------------------------------

// d (query-major, n_query x n_ref) = DifferenceColumn of every query.
SeqSlamError ComputeDifferenceMatrix(std::span<const float> reference, std::span<const float> query,
                                     int dim, std::span<float> d);

// Enhances every column of d into out (same layout).
SeqSlamError EnhanceDifferenceMatrix(std::span<const float> d, int n_ref, int n_query,
                                     int contrast_window, std::span<float> out);

// SeqSLAM from a difference matrix d (query-major): enhancement then, for every query
// frame t, the search over the window around it. matches.size() must be n_query.
SeqSlamError SeqSlamFromDifferences(std::span<const float> d, int n_ref, int n_query,
                                    const SeqSlamParams& params, SeqSlamWindow window,
                                    std::span<SeqSlamMatch> matches);

// SeqSLAM from descriptors (reference and query stored row by row, dim floats each).
// Allocates the difference matrices (n_ref x n_query floats, twice): an offline tool.
SeqSlamError BatchSeqSlam(std::span<const float> reference, std::span<const float> query, int dim,
                          const SeqSlamParams& params, SeqSlamWindow window,
                          std::span<SeqSlamMatch> matches);

// ---- Streaming engine (firmware) -------------------------------------------------------

// How the streaming engine stores the route database. The difference column reads the
// whole database every frame, so at large N its size is the step's cost.
enum class ReferenceStorage : std::uint8_t {
  kFloat32,   // exact: 4 bytes per element
  kBFloat16,  // rounded to 8 significant bits (relative error <= 2^-9): half the memory and
              // the memory traffic; far below the noise of any image descriptor
  // Codes with a power-of-two scale per row (EncodeCodes): dim + 1 bytes a row for kCodes8
  // (square law, error about sqrt(v max(row)) / 181), 2 dim + 1 for kCodes16 (linear,
  // <= max(row) / 65535). The route database stores the descriptors as 16-bit codes
  // (format version 5), so a route loads into kCodes16 exactly as it was taught. For
  // amplitude spectra (values >= 0).
  kCodes8,
  kCodes16,
};

// "float32", "bfloat16", "codes8", "codes16": the one spelling ([capacities] route_storage,
// experiment --route-storage, reports).
constexpr const char* ReferenceStorageName(ReferenceStorage storage) {
  switch (storage) {
    case ReferenceStorage::kFloat32:
      return "float32";
    case ReferenceStorage::kBFloat16:
      return "bfloat16";
    case ReferenceStorage::kCodes8:
      return "codes8";
    case ReferenceStorage::kCodes16:
      return "codes16";
  }
  return "?";
}
// Bytes a row of `dim` elements takes in `storage`.
std::size_t ReferenceRowBytes(ReferenceStorage storage, int dim);

// The taught route's descriptors as a matcher holds them (float32 or bfloat16), one row
// per frame; shared by StreamingSeqSlam and RouteFilter. Allocate is the only allocation;
// the rest indexes without checks (the engines check their bounds).
class ReferenceRows {
 public:
  void Allocate(int dim, int capacity, ReferenceStorage storage);
  // Row `row` becomes `descriptor` (dim floats; rounded to bfloat16 or encoded as codes
  // when stored so).
  void Store(int row, std::span<const float> descriptor);
  // Row `to` becomes a copy of row `from`.
  void Copy(int from, int to);
  // out[0 .. count) = DifferenceColumn of rows first_row .. first_row + count - 1.
  void Differences(std::span<const float> query, int first_row, int count, float* out) const;
  // Row `row` as dim floats (exact for both storages).
  void RowAsFloat(int row, float* out) const;

  int dim() const { return dim_; }
  ReferenceStorage storage() const { return storage_; }
  std::size_t AllocatedBytes() const;

 private:
  int dim_ = 0;
  ReferenceStorage storage_ = ReferenceStorage::kFloat32;
  std::vector<float> float32_;           // capacity x dim (kFloat32)
  std::vector<std::uint16_t> bfloat16_;  // capacity x dim (kBFloat16)
  std::vector<std::uint8_t> codes8_;     // capacity x dim (kCodes8)
  std::vector<std::uint16_t> codes16_;   // capacity x dim (kCodes16)
  std::vector<std::int8_t> exponents_;   // capacity (kCodes8, kCodes16)
};

class StreamingSeqSlam {
 public:
  // Allocates everything (the only allocation): the database of `capacity` descriptors of
  // `dim` elements, the ring of ds enhanced columns and the per-step scratch.
  SeqSlamError Init(const SeqSlamParams& params, int dim, int capacity,
                    ReferenceStorage storage = ReferenceStorage::kFloat32);

  // Appends a reference descriptor (the taught route, in order). Forgets the query
  // history: the ring's columns were computed against the smaller database.
  SeqSlamError AddReference(std::span<const float> descriptor);
  void ClearReferences();
  // Forgets the query history (e.g. after a gap in the frames).
  void ResetQueries();

  // One query frame: difference column, enhancement, trajectory search over the last ds
  // frames (trailing window). `out->valid` is false until ds frames have been seen.
  // O(N * (dim + velocities * ds)), allocates nothing. The three run interleaved, a few
  // hundred reference rows at a time, so the enhancement and the search work on rows
  // still in cache while the database streams in (the same floats as running them one
  // after the other: see ColumnEnhancer and TrajectorySearch::ScoreStarts).
  SeqSlamError Step(std::span<const float> query, SeqSlamMatch* out);

  int size() const { return size_; }
  int capacity() const { return capacity_; }
  ReferenceStorage storage() const { return rows_.storage(); }
  int dim() const { return dim_; }
  int frames_in_window() const { return count_; }

  // Bytes Init allocates per reference frame: descriptor, ds ring entries, two scratch
  // floats (the difference column and the per-start scores).
  static std::size_t BytesPerReference(const SeqSlamParams& params, int dim,
                                       ReferenceStorage storage = ReferenceStorage::kFloat32);
  std::size_t AllocatedBytes() const;

 private:
  SeqSlamParams params_;
  TrajectorySearch search_;
  ColumnEnhancer enhancer_;
  int dim_ = 0;
  int capacity_ = 0;
  int size_ = 0;
  int head_ = 0;                     // ring slot the next column goes into
  int count_ = 0;                    // columns in the ring (<= ds)
  ReferenceRows rows_;               // the route database
  std::vector<float> ring_;          // ds x capacity enhanced columns
  std::vector<float> difference_;    // capacity
  std::vector<float> scores_;        // capacity
  std::vector<const float*> order_;  // ds column pointers, oldest first
};

}  // namespace skyloc::dsp
