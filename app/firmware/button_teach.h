// `skyloc repeat` with a teach button ([status] button_line): repeat on the route until a
// debounced press, then teach a new route into the same path until the next press, commit
// it, load it and repeat on it; and so on, until a signal, the end of the source or a
// fatal error. Without a route it waits for the first press (frames are captured and
// dropped, the status lines stay safe).
//
// The old route is never at risk: the new one goes to FILE.tmp (RouteDbWriter's replace
// mode) and is renamed over FILE only when it is committed with at least one frame; a
// teach that fails leaves FILE untouched.
#pragma once

#include <cstddef>

#include "firmware/frame_loop.h"
#include "firmware/pipeline.h"
#include "firmware/route_db.h"

namespace skyloc::firmware {

struct ButtonTeachSetup {
  drivers::Camera* camera = nullptr;
  drivers::StatusOutput* status = nullptr;  // must have a button
  Pipeline* pipeline = nullptr;
  // Holds the loaded route (empty: none yet); reloaded after every teach. Allocated to
  // the route capacity, which also caps a teach.
  RouteFrames* route = nullptr;
  const char* route_path = nullptr;
  std::size_t flush_every = 50;
  FrameSink* sink = nullptr;  // teach and repeat frames; none while waiting
  drivers::AttitudeSource* attitude = nullptr;
  const char* label = "skyloc repeat";
};

struct ButtonTeachReport {
  LoopSummary loop;            // over every phase
  unsigned routes_taught = 0;  // committed and loaded
};

// `options` is the repeat loop's (its mode and button are set here; max_frames applies to
// each phase). The loop gives the debouncer times from the pipeline's clock
// (setup.pipeline->clock()), which must be the one the button's edges are stamped with.
Status RunRepeatWithButton(const ButtonTeachSetup& setup, const LoopOptions& options,
                           ButtonDebouncer* button, ButtonTeachReport* report);

}  // namespace skyloc::firmware
