#include "skyloc/drivers/status_output.h"

namespace skyloc::drivers {

const char* LocalisationStateName(LocalisationState state) {
  switch (state) {
    case LocalisationState::kLost:
      return "LOST";
    case LocalisationState::kSearching:
      return "SEARCHING";
    case LocalisationState::kLocalised:
      return "LOCALISED";
  }
  return "UNKNOWN";
}

}  // namespace skyloc::drivers
