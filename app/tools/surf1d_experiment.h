// The 1D SURF paper's classification experiment (Anderson et al. 2012, section 4.1; issue
// 13 item 5) in the simulated city: a robot turns on the spot and takes `images_per_place`
// images evenly spaced over 360 degrees (the paper: 88, about 4 degrees apart); every pair
// of images is scored by 1D SURF (nearest neighbour, and nearest neighbour with RANSAC)
// and the scores are judged by their ROC curve against which pairs truly show the same
// landmark. Two cameras:
//
//  - forward pinhole, the paper's Nao camera: 640 x 480, 47.8 degrees across the width.
//    The strip is the paper's: every 4th column, the mean of a 30-row band centred on the
//    horizon row, which comes from the camera's attitude (the true pose: the paper reads
//    it from the robot's kinematics). The camera is pitched `pitch_deg` with a random
//    +-`attitude_jitter_deg` roll and pitch per image, so the horizon moves and tilts.
//    A pair matches when the two headings are less than `match_below_deg` apart (the
//    paper: 20 degrees, >= 58 % of the horizon shared); only pairs at the same place are
//    scored, as in the paper's single-place bank.
//  - upward fisheye (the product's camera) and its 360-degree strip (dsp::HorizonStrip,
//    the [heading] defaults), level: every heading at a place sees the whole panorama, so
//    a pair matches when it is at the same place, and the other place's images are the
//    non-matching pairs.
//
// The forward strip is not periodic but dsp::Surf1d treats strips as circular, so it is
// padded on both sides to three times its length with a linear ramp from its last value
// back to its first (no step at the seam, zero second derivative inside the ramp), and
// features detected in the padding are dropped. Offline work: everything here allocates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/dsp/surf1d.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/renderer.h"
#include "tools/experiment.h"

namespace skyloc::tools {

struct Surf1dExperimentOptions {
  int images_per_place = 88;
  int places = 2;  // points along the city's route, evenly spread over its vertices
  double match_below_deg = 20.0;
  double camera_height_m = 1.0;
  std::uint64_t world_seed = 1;
  sim::Lighting lighting;  // the renderer's defaults
  // Forward pinhole camera.
  int width = 640;
  int height = 480;
  double fov_deg = 47.8;
  int column_step = 4;
  int band_rows = 30;
  double pitch_deg = -5.0;  // nose down
  double attitude_jitter_deg = 1.0;
  // Upward fisheye (DefaultSimLens at this size) and its strip.
  int fisheye_width = 640;
  int fisheye_height = 480;
  dsp::HorizonStripOptions fisheye_strip;
  dsp::Surf1dOptions surf;
  dsp::LandmarkMatchOptions match;
};

// One camera's pairs and their ROC.
struct Surf1dCameraResult {
  std::string camera;                   // e.g. "forward pinhole 640x480, 47.8 deg"
  int strip_columns = 0;                // without the padding
  double mean_features = 0;             // per image
  std::vector<dsp::ScoredPair> nn;      // NN score (sum of 1 / distance) of every pair
  std::vector<dsp::ScoredPair> ransac;  // NN with RANSAC (0 when RANSAC found no line)
  std::vector<dsp::RocPoint> roc_nn, roc_ransac;
  double auc_nn = 0, auc_ransac = 0;
  int matched_pairs = 0, unmatched_pairs = 0;
  // Forward camera only: the AUCs with the unmatched pairs restricted to views that share
  // nothing (headings at least the field of view apart), leaving out the pairs that
  // overlap by less than the paper's 58 % but still see some of the same scene.
  double auc_nn_disjoint = 0, auc_ransac_disjoint = 0;
  int disjoint_pairs = 0;
};

// The horizon row of image column x for a pinhole lens on a robot at `pose`: the row where
// the column's rays are level in the world. False when the horizon is not in the image or
// the column's rays are all on one side of it (a camera looking straight up or down).
bool PinholeHorizonRow(const dsp::Lens& lens, const drivers::Pose& pose, double x, double* row);

Status RunSurf1dExperiment(const Surf1dExperimentOptions& options, Surf1dCameraResult* forward,
                           Surf1dCameraResult* fisheye, ProgressFn progress = nullptr);

}  // namespace skyloc::tools
