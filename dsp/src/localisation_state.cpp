#include "skyloc/dsp/localisation_state.h"

namespace skyloc::dsp {

const char* LocalisationStateName(LocalisationState state) {
  switch (state) {
    case LocalisationState::kLost:
      return "LOST";
    case LocalisationState::kSearching:
      return "SEARCHING";
    case LocalisationState::kLocalised:
      return "LOCALISED";
  }
  return "?";
}

const char* StateMachineErrorMessage(StateMachineError error) {
  switch (error) {
    case StateMachineError::kOk:
      return "ok";
    case StateMachineError::kBadConfidence:
      return "enter_confidence and stay_confidence must be in 0..1, with stay_confidence not "
             "above enter_confidence";
    case StateMachineError::kBadUniqueness:
      return "max_uniqueness must be in 0..1";
    case StateMachineError::kBadCounts:
      return "confirm_frames, drop_frames and lost_frames must be at least 1";
    case StateMachineError::kBadVelocity:
      return "the velocity band must have 0 <= vmin <= vmax and a tolerance of at least 0";
  }
  return "unknown state machine error";
}

StateMachineError LocalisationStateMachine::Init(const StateMachineParams& p) {
  const bool unit = p.enter_confidence >= 0 && p.enter_confidence <= 1 && p.stay_confidence >= 0 &&
                    p.stay_confidence <= 1;
  if (!unit || p.stay_confidence > p.enter_confidence)
    return StateMachineError::kBadConfidence;
  if (!(p.max_uniqueness >= 0 && p.max_uniqueness <= 1))
    return StateMachineError::kBadUniqueness;
  if (p.confirm_frames < 1 || p.drop_frames < 1 || p.lost_frames < 1)
    return StateMachineError::kBadCounts;
  if (!(p.vmin >= 0 && p.vmin <= p.vmax && p.index_tolerance >= 0))
    return StateMachineError::kBadVelocity;
  params_ = p;
  Reset();
  return StateMachineError::kOk;
}

void LocalisationStateMachine::Reset() {
  state_ = LocalisationState::kLost;
  has_anchor_ = false;
  streak_ = 0;
  misses_ = 0;
}

bool LocalisationStateMachine::Good(const MatchObservation& obs) const {
  return obs.index >= 0 && obs.confidence >= params_.enter_confidence &&
         obs.uniqueness <= params_.max_uniqueness;
}

bool LocalisationStateMachine::Keeps(const MatchObservation& obs) const {
  return obs.index >= 0 && obs.confidence >= params_.stay_confidence &&
         obs.uniqueness <= params_.max_uniqueness;
}

bool LocalisationStateMachine::Consistent(const MatchObservation& obs) const {
  if (!has_anchor_)
    return false;
  // Frames since the anchor; a repeated or older frame number counts as one step.
  const double gap =
      obs.frame > anchor_.frame ? static_cast<double>(obs.frame - anchor_.frame) : 1.0;
  const double moved = static_cast<double>(obs.index - anchor_.index);
  return moved >= params_.vmin * gap - params_.index_tolerance &&
         moved <= params_.vmax * gap + params_.index_tolerance;
}

LocalisationState LocalisationStateMachine::Update(const MatchObservation& obs) {
  switch (state_) {
    case LocalisationState::kLost:
      if (Good(obs)) {
        Accept(obs);
        streak_ = 1;
        state_ = LocalisationState::kSearching;
      }
      break;
    case LocalisationState::kSearching:
      if (Good(obs)) {
        // A good frame that does not continue the candidate's track starts a new one.
        streak_ = Consistent(obs) ? streak_ + 1 : 1;
        Accept(obs);
      } else if (++misses_ >= params_.lost_frames) {
        Reset();
      }
      break;
    case LocalisationState::kLocalised:
      if (Keeps(obs) && Consistent(obs)) {
        Accept(obs);
      } else if (++misses_ >= params_.drop_frames) {
        state_ = LocalisationState::kSearching;
        has_anchor_ = false;
        streak_ = 0;
        misses_ = 0;
      }
      break;
  }
  if (state_ == LocalisationState::kSearching && streak_ >= params_.confirm_frames)
    state_ = LocalisationState::kLocalised;
  return state_;
}

}  // namespace skyloc::dsp
