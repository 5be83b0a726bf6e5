// From per-frame match results to LOST / SEARCHING / LOCALISED, with hysteresis.
// docs/STATE_MACHINE.md explains the rules and the defaults; in short:
//   - a frame is *good* when its match is confident and unique enough,
//   - it is *consistent* when the matched route index moved by what the robot can have
//     travelled since the last accepted match (the SeqSLAM velocity band, plus slack),
//   - confirm_frames good, consistent frames in a row make LOCALISED; once localised, a
//     lower confidence keeps it (stay_confidence), and only drop_frames misses in a row
//     fall back to SEARCHING; lost_frames misses in a row while searching give LOST.
// Pure and allocation-free: one Update() per frame.
#pragma once

#include <cstdint>

namespace skyloc::dsp {

enum class LocalisationState : std::uint8_t { kLost, kSearching, kLocalised };

const char* LocalisationStateName(LocalisationState state);

struct MatchObservation {
  std::uint64_t frame = 0;  // query frame number; gaps mean dropped frames
  std::int64_t index = -1;  // best route index; < 0: no match this frame
  float uniqueness = 1.0f;  // best / second-best score (OpenSeqSLAM): lower is more unique
  float confidence = 0.0f;  // in [0, 1], higher is better
};

struct StateMachineParams {
  float enter_confidence = 0.3f;
  float stay_confidence = 0.15f;
  float max_uniqueness = 0.95f;
  int confirm_frames = 5;
  int drop_frames = 5;
  int lost_frames = 10;
  double vmin = 0.8;  // route frames per query frame
  double vmax = 1.2;
  double index_tolerance = 2.0;  // route frames

  bool operator==(const StateMachineParams&) const = default;
};

enum class StateMachineError : std::uint8_t {
  kOk,
  kBadConfidence,  // thresholds outside [0, 1] or stay > enter
  kBadUniqueness,
  kBadCounts,    // a frame count < 1
  kBadVelocity,  // vmin > vmax, negative, or negative tolerance
};

const char* StateMachineErrorMessage(StateMachineError error);

class LocalisationStateMachine {
 public:
  StateMachineError Init(const StateMachineParams& params);
  LocalisationState Update(const MatchObservation& obs);
  void Reset();

  LocalisationState state() const { return state_; }
  // The route index of the last accepted match (LOCALISED or the SEARCHING candidate);
  // -1 when there is none.
  std::int64_t anchor_index() const { return has_anchor_ ? anchor_.index : -1; }

 private:
  bool Good(const MatchObservation& obs) const;
  bool Keeps(const MatchObservation& obs) const;
  bool Consistent(const MatchObservation& obs) const;
  void Accept(const MatchObservation& obs) {
    anchor_ = obs;
    has_anchor_ = true;
    misses_ = 0;
  }

  StateMachineParams params_;
  LocalisationState state_ = LocalisationState::kLost;
  MatchObservation anchor_;
  bool has_anchor_ = false;
  int streak_ = 0;  // good, consistent frames in a row while searching
  int misses_ = 0;  // frames in a row that did not count
};

}  // namespace skyloc::dsp
