// The route filter: where on the taught route the robot is, from a stream of descriptors
// taken at a fixed frame rate while the robot accelerates, cruises, stops and runs at
// another speed than when it was taught. The firmware's default matcher; docs/SEQSLAM.md
// ("The route filter") argues the design with measurements. In short:
//
//  1. Keyframes. A taught route sampled in time holds runs of nearly identical frames
//     wherever the robot stood. FinishRoute() merges each such run into one route row: a
//     frame joins the current row while its mean absolute difference to the row's first
//     frame is at most keyframe_noise_factor x the route's noise floor, the 10th
//     percentile of the differences between consecutive frames (the sensor noise of a
//     standing robot when the route has stops), and at most half their median (the
//     change of a typical frame: on a route without stops, or of unrelated frames,
//     little or nothing merges). Frames in motion are kept, so a match keeps its
//     precision in frames. A matched row of one frame reports that frame; a merged row
//     reports where in its run the evidence puts the robot (5.).
//  2. Emission. Each query's difference column (mean absolute difference to every row,
//     as SeqSLAM's) is z-scored over the whole route: z = (d - mean) / std. No local
//     contrast window, so the minimum stays where the descriptor puts it (OpenSeqSLAM's
//     +-R/2 window moves it to the edge of a wide basin of alike frames).
//  3. Motion. A min-sum filter over rows (Viterbi's recursion, run forward only) with a
//     memory of ds frames:
//        cost_t(i) = z_t(i) + lambda * min_{k = 0..K} cost_{t-1}(i - k),  lambda = 1 - 1/ds
//     so the position may stand still (k = 0) or advance up to K = max_advance rows per
//     frame, with any speed profile in between, not one straight line per window. cost_t(i)
//     is the lowest discounted sum of z along any such path ending at row i; old evidence
//     fades with lambda, so the filter re-localises within about ds frames after a kidnap
//     without a special case. ds = 1 is single-image nearest neighbour (lambda = 0).
//  4. Confidence. The best row against the runner-up, the best row outside the best's
//     basin (the rows around it whose cost rises monotonically away from it) and outside
//     +-uniqueness_window/2: margin = cost_second - cost_best, how many column standard
//     deviations of evidence the best path is ahead by. confidence = 1 - exp(-margin),
//     uniqueness = exp(-margin) (so confidence = 1 - uniqueness, as for SeqSLAM). Right
//     after a reset the costs hold little evidence, so the confidence starts low and grows.
//     The track: a best row more than uniqueness_window/2 rows behind the last frame's,
//     or more than K + uniqueness_window/2 ahead, moved against the motion model: another
//     path of the filter took the lead, and it has not yet shown it keeps it. The
//     confidence is scaled by min(1, k / (2 ds)) on the k-th frame of a track (k = 1 where
//     it began, also the first frame after a reset): where the evidence is flat and the
//     best row swings between two paths, no frame of the swing is trusted.
//  5. The frame a merged row reports. A row that merged a stop spans many taught frames;
//     its middle is right while the robot stands there, and half the stop wrong while it
//     arrives or leaves (the frames just before and after the stop are where it is).
//     With the same weights as the confidence, w = exp(-(cost_neighbour - cost_best))
//     for the rows before and after (0 past the route's ends), the position in the run
//     is p = (w_after - w_before) / (1 + w_before + w_after), in -1/2..1/2: the mean row
//     offset over the best and its two neighbours. The row reports frame
//     first + floor((1/2 + p) (last - first)): its middle when both neighbours are far
//     behind (p = 0), its last frame when the next row is as good (leaving), its first
//     when the row before is (arriving). A row of one frame reports that frame.
//  6. The search window (optional, off by default; docs/SEQSLAM.md, Design 6).
//     On a long route most of a frame's time is the difference column (rows x dim). With
//     search_window W > 0 and refresh_frames F, a frame compares the query with the rows
//     within +-W of the last frame's best row and with one slice of F (rows f x n / F ..
//     (f + 1) x n / F - 1 on the f-th frame of each cycle of F), so every row's
//     difference is at most F - 1 frames old. Every other row keeps its last difference,
//     and 2.-5. run over the whole column as without the window: one filter, and the
//     runner-up still sees the whole route. The first frame after a reset compares every
//     row (no difference is used before it was computed). A kidnap is found when the
//     slices reach the new place: up to F frames later than without the window.
//
// Fixed memory (everything at Init), no allocation in AddReference, FinishRoute or Step.
// Step is O(rows x (dim + K)), with the window O((2 W + 1 + rows / F) x dim + rows x K).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/seqslam.h"

namespace skyloc::dsp {

inline constexpr int kMaxAdvance = 64;
inline constexpr int kMaxSearchWindow = 1000000;
inline constexpr int kMaxRefreshFrames = 1000;

struct RouteFilterParams {
  int sequence_length = 10;  // ds: frames of evidence the filter remembers (1..1000)
  // K: the most route rows the position may move forward in one query frame (1..64). A
  // repeat run up to K times faster than the taught one is followed; slower runs and
  // stops need no setting. 8: a 3x faster repeat through the stretches where the taught
  // run was still accelerating (rows there are closer than at cruise speed); measured
  // in docs/SEQSLAM.md.
  int max_advance = 8;
  int uniqueness_window = 10;  // runner-up outside +-window/2 rows of the best (0..10000)
  // Merge a frame into the current route row while it differs from the row's first
  // frame by at most this x the route's noise floor (0..100; 0 keeps every frame).
  float keyframe_noise_factor = 2.0f;
  // The search window (6. above), for routes too long to compare with every frame: the
  // rows within +-search_window of the last best row are compared with every frame, every
  // other row once every refresh_frames frames (a slice of rows / refresh_frames rows a
  // frame, in turn) and keeps its last difference in between. 0 (and refresh_frames 0):
  // off, every row every frame. search_window 0..kMaxSearchWindow; refresh_frames
  // 1..kMaxRefreshFrames with a window, 0 without.
  int search_window = 0;
  int refresh_frames = 0;

  bool operator==(const RouteFilterParams&) const = default;
};

SeqSlamError ValidateRouteFilterParams(const RouteFilterParams& params);

class RouteFilter {
 public:
  // Allocates everything (the only allocation): the route of `capacity` frames of `dim`
  // elements, the row table, two cost columns and the difference column.
  SeqSlamError Init(const RouteFilterParams& params, int dim, int capacity,
                    ReferenceStorage storage = ReferenceStorage::kFloat32);

  // Appends a taught frame (in order). The route is not matched against until
  // FinishRoute() has merged it into rows.
  SeqSlamError AddReference(std::span<const float> descriptor);
  // Merges stationary runs into rows (docs above, 1.) and forgets the query history.
  // O(frames x dim) plus a median; allocates nothing. Again on a finished route: only
  // forgets the query history.
  SeqSlamError FinishRoute();
  void ClearReferences();
  // Forgets the query history (a gap in the frames, a new run).
  void ResetQueries();

  // One query frame: difference column, z-score, filter update, best row and runner-up.
  // Valid from the first frame (its confidence grows with the evidence).
  SeqSlamError Step(std::span<const float> query, SeqSlamMatch* out);

  int frames() const { return frames_; }  // taught frames added
  int rows() const { return rows_; }      // route rows after FinishRoute
  bool finished() const { return finished_; }
  int capacity() const { return capacity_; }
  int dim() const { return dim_; }
  ReferenceStorage storage() const { return route_.storage(); }
  // The taught frames merged into row r: first .. last (inclusive).
  int row_first_frame(int r) const { return first_frame_[static_cast<std::size_t>(r)]; }
  int row_last_frame(int r) const { return last_frame_[static_cast<std::size_t>(r)]; }
  // The merge threshold FinishRoute used (0: nothing merged).
  float keyframe_threshold() const { return keyframe_threshold_; }

  // The rows whose differences the last Step computed (6.): the window and this frame's
  // slice; every row on a frame that compared them all.
  bool RowCompared(int r) const {
    return (r >= compared_[0] && r < compared_[1]) || (r >= compared_[2] && r < compared_[3]);
  }
  // How many rows the last Step compared with the query (the window and the slice once).
  int rows_compared() const { return rows_compared_; }

  // The frame a match to row `best` reports, from the costs of the last Step (docs
  // above, 5.).
  int ReportedFrame(int best) const;

  static std::size_t BytesPerReference(int dim,
                                       ReferenceStorage storage = ReferenceStorage::kFloat32);
  std::size_t AllocatedBytes() const;

 private:
  RouteFilterParams params_;
  int dim_ = 0;
  int capacity_ = 0;
  int frames_ = 0;
  int rows_ = 0;
  bool finished_ = false;
  int steps_ = 0;                   // query frames since the last reset
  int track_row_ = -1;              // the best row of the last step (-1: none since the reset)
  int track_frames_ = 0;            // steps since the best row last jumped
  int refresh_phase_ = 0;           // the slice the next windowed frame compares (0..F-1)
  int compared_[4] = {0, 0, 0, 0};  // rows the last Step compared: [0, 1) and [2, 3)
  int rows_compared_ = 0;
  float lambda_ = 0;  // 1 - 1/ds
  float keyframe_threshold_ = 0;
  ReferenceRows route_;            // taught frames, then (FinishRoute) the keyframe rows
  std::vector<int> first_frame_;   // capacity
  std::vector<int> last_frame_;    // capacity
  std::vector<float> cost_;        // capacity: cost after the last step
  std::vector<float> previous_;    // capacity: cost before it
  std::vector<float> difference_;  // capacity: this frame's differences
  std::vector<float> key_;         // dim: a row's descriptor as floats

  // Step's first part: this frame's differences (every row, or the window and a slice).
  void CompareRows(std::span<const float> query);
};

}  // namespace skyloc::dsp
