// What a session says on stderr: the start-up line and its warnings, the shut-down
// reports (the route committed or not, the recording, the attitude source) and the
// closing summary. The session (session.cpp) decides; these lines only say it.
#pragma once

#include <cstddef>

#include "firmware/frame_recorder.h"
#include "firmware/route_db.h"
#include "firmware/session.h"
#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/camera.h"

namespace skyloc::firmware {

// The one start-up line: what the run reads, shows and writes, so a simulated or wrong
// device cannot go unnoticed; then a loud warning for a live mode on a simulation.
void PrintStartup(const SessionArgs& args, const Config& config, const drivers::CameraInfo& info,
                  const RouteDbWriter& writer, std::size_t loaded_frames);

// "label: warning: MESSAGE" when `s` is an error; nothing when it is ok.
void PrintWarning(const char* label, const Status& s);

// When a teach replaced a FILE.db.tmp that a killed teach left: what it held.
void PrintReplacedTmp(const char* label, const char* route_path, const RouteTmpReport& tmp);

// After teach's Commit(): how many frames the route keeps and, when the commit failed,
// whether they are committed and what to do.
void PrintCommit(const SessionArgs& args, const RouteDbWriter& writer, const Status& committed);

// After the recording is closed: frames written and dropped, and why it stopped.
void PrintRecording(const char* label, const FrameRecorder& recorder, const Status& closed);

// The attitude source's counters: frames with an attitude and those described as level.
void PrintAttitude(const char* label, const drivers::AttitudeSource& source);

// The run's closing lines: frames by state and capture errors, and the evaluation when
// there was one.
void PrintSummary(const SessionArgs& args, const SessionReport& r);

}  // namespace skyloc::firmware
