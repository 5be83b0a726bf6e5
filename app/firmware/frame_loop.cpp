#include "firmware/frame_loop.h"

#include <cstdio>
#include <thread>

#include "skyloc/platform/signals.h"

namespace skyloc::firmware {

namespace {

// What this loop has put on the status lines, so it can keep them moving between frames.
enum class Shown : std::uint8_t { kNothing, kState, kTeaching };

Nanoseconds Mod(Nanoseconds t, Nanoseconds period) {
  Nanoseconds phase = t % period;
  return phase < Nanoseconds(0) ? phase + period : phase;
}

// Teach with show_teaching: SEARCHING for the first half of every kTeachingPeriod, the
// safe state for the second.
Status ShowTeaching(drivers::StatusOutput& status, Nanoseconds now) {
  if (Mod(now, kTeachingPeriod) < kTeachingPeriod / 2)
    return status.Show(drivers::LocalisationState::kSearching, 0.0f, now);
  return status.SafeState();
}

// When the lines next change if no frame comes first.
Nanoseconds NextLineChange(const drivers::StatusOutput* status, Shown shown, Nanoseconds now) {
  if (status == nullptr || shown == Shown::kNothing)
    return drivers::StatusOutput::kNever;
  const Nanoseconds blink = status->NextChange(now);
  if (shown == Shown::kState)
    return blink;
  const Nanoseconds half = kTeachingPeriod / 2;
  const Nanoseconds teaching = now + (half - Mod(now, half));
  return teaching < blink ? teaching : blink;
}

// The lines as they are at `now` (a blink edge, or the teaching indicator's half period).
Status MoveLines(drivers::StatusOutput* status, Shown shown, Nanoseconds now) {
  if (status == nullptr || shown == Shown::kNothing)
    return Status::Ok();
  if (shown == Shown::kTeaching)
    return ShowTeaching(*status, now);
  return status->Refresh(now);
}

// The next frame, waiting until `deadline` at most, and moving the status lines at each
// of their edges before it. A failure to move them goes to *lines_failed (fatal, as a
// failed Show() is); the capture's own result is returned.
Result<drivers::Frame> CaptureMovingLines(drivers::Camera& camera, drivers::StatusOutput* status,
                                          Shown shown, const Clock& clock, Nanoseconds deadline,
                                          Status* lines_failed) {
  for (;;) {
    const Nanoseconds now = clock.Now();
    const Nanoseconds edge = NextLineChange(status, shown, now);
    const Nanoseconds until = edge < deadline ? edge : deadline;
    Result<drivers::Frame> captured = camera.Capture(until > now ? until - now : Nanoseconds(0));
    if (edge >= deadline || captured.ok() ||
        captured.status().code() != StatusCode::kDeadlineExceeded)
      return captured;
    // Past the deadline, a camera that gave up before the time it was given (its own
    // time-out, a fake that does not wait) or a signal: the caller decides.
    const Nanoseconds woken = clock.Now();
    if (woken >= deadline || woken < until || StopRequested())
      return captured;
    if (Status moved = MoveLines(status, shown, woken); !moved.ok()) {
      *lines_failed = moved;
      return captured;
    }
  }
}

// Sleeps until `due` (pacing), moving the status lines at each of their edges before it.
Status SleepMovingLines(drivers::StatusOutput* status, Shown shown, const Clock& clock,
                        Nanoseconds due) {
  Nanoseconds now = clock.Now();
  while (due > now) {
    const Nanoseconds edge = NextLineChange(status, shown, now);
    const Nanoseconds wake = edge < due ? edge : due;
    std::this_thread::sleep_for(wake - now);
    if (wake == due)
      break;
    const Nanoseconds woken = clock.Now();
    now = woken > wake ? woken : wake;  // a ManualClock does not move while we sleep
    SKYLOC_TRY(MoveLines(status, shown, now));
  }
  return Status::Ok();
}

// SIGUSR1: the latency table and the devices' counters so far, the run going on.
void PrintReportIfAsked(const LatencyTable& latency, const LoopOptions& options,
                        std::uint64_t frames) {
  if (!TakeReportRequest())
    return;
  std::fprintf(stderr, "skyloc: latency after %llu frames (SIGUSR1; the run goes on):\n",
               static_cast<unsigned long long>(frames));
  latency.Print(stderr);
  if (options.devices != nullptr)
    options.devices->Print(stderr);
}

// The teach button's pending edges through its debouncer: true when a press was accepted.
Result<bool> ButtonPressed(drivers::StatusOutput& status, ButtonDebouncer& button,
                           const Clock& clock) {
  for (;;) {
    Result<drivers::ButtonEvent> edge = status.ReadButtonEvent();
    if (!edge.ok()) {
      if (edge.status().code() == StatusCode::kDeadlineExceeded)
        break;  // no edge pending
      Status failed = edge.status();
      return failed.AddContext("the teach button");
    }
    button.OnEdge(*edge);
  }
  return button.TakePress(clock.Now());
}

// The attitude at each frame's time, said once when it goes missing and once when it is
// back; without one the frame is described as if level (the cap about the body's z axis),
// never dropped.
class FrameAttitudes {
 public:
  // The frame's attitude, kept in `*storage`; null when there is none (counted in
  // `*missing`).
  const dsp::Attitude* At(drivers::AttitudeSource& source, const drivers::Frame& frame,
                          dsp::Attitude* storage, std::uint64_t* missing) {
    Result<dsp::Attitude> a = source.At(frame);
    if (a.ok()) {
      *storage = *a;
      if (outage_)
        std::fprintf(stderr, "skyloc: attitude %s is back at frame %llu\n", source.name(),
                     static_cast<unsigned long long>(frame.sequence));
      outage_ = false;
      return storage;
    }
    ++*missing;
    if (!outage_)
      std::fprintf(stderr,
                   "skyloc: warning: %s: frames are described as if level until it returns\n",
                   a.status().message());
    outage_ = true;
    return nullptr;
  }

 private:
  bool outage_ = false;
};

// The run of failed captures and frames the loop is riding out.
struct Retries {
  int errors_in_a_row = 0;
  Nanoseconds unavailable_since{-1};
};

enum class AfterCaptureError : std::uint8_t { kRetry, kEnd, kFail };

// A failed capture (`code`, the Capture() call between t0 and t1): kEnd when the source
// ended (end_of_source) or a signal cut the wait; kRetry for a time-out or a corrupt frame
// (up to max_consecutive_errors in a row) and for an unplugged camera within
// reconnect_timeout, counted in capture_errors; else kFail, the error ends the run. No
// frame means no localisation: the lines go to the safe state until frames flow again,
// and the SeqSLAM sequence starts over (it needs consecutive frames).
AfterCaptureError OnCaptureError(StatusCode code, Nanoseconds t0, Nanoseconds t1,
                                 const LoopOptions& options, drivers::StatusOutput* status,
                                 Pipeline& pipeline, Shown* shown, Retries* retries,
                                 LoopSummary* s) {
  if (code == StatusCode::kOutOfRange) {
    s->end_of_source = true;
    return AfterCaptureError::kEnd;
  }
  // A signal interrupted the wait: the loop condition sees the flag.
  if (StopRequested())
    return AfterCaptureError::kEnd;
  if (status != nullptr)
    (void)status->SafeState();
  *shown = Shown::kNothing;
  pipeline.ResetTracking();
  if (code == StatusCode::kDataLoss && options.recorded)
    return AfterCaptureError::kFail;
  if ((code == StatusCode::kDeadlineExceeded || code == StatusCode::kDataLoss) &&
      ++retries->errors_in_a_row < options.max_consecutive_errors) {
    ++s->capture_errors;
    return AfterCaptureError::kRetry;
  }
  if (code == StatusCode::kUnavailable && options.reconnect_timeout.count() > 0) {
    if (retries->unavailable_since.count() < 0)
      retries->unavailable_since = t1;
    if (t1 - retries->unavailable_since < options.reconnect_timeout) {
      ++s->capture_errors;
      // A driver that reports the loss without waiting must not make this spin.
      if (t1 - t0 < std::chrono::milliseconds(10))
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return AfterCaptureError::kRetry;
    }
  }
  return AfterCaptureError::kFail;
}

// teach: the frame described and appended to the route (its time and pose with it); with
// show_teaching the lines show that it is teaching.
Status TeachFrame(const drivers::Frame& frame, const dsp::Attitude* attitude, bool show_teaching,
                  drivers::StatusOutput* status, Pipeline& pipeline, RouteDbWriter& route,
                  FrameResult* result, Shown* shown) {
  SKYLOC_TRY(pipeline.Describe(frame.image, result, attitude));
  RouteFrameMeta meta;
  meta.timestamp_ns = static_cast<std::uint64_t>(frame.timestamp.count());
  meta.pose = frame.pose;
  StageTimer timer(pipeline.latency(), pipeline.stages().output, pipeline.clock());
  SKYLOC_TRY(route.Append(meta, pipeline.descriptor(), pipeline.strip()));
  if (status != nullptr && show_teaching) {
    SKYLOC_TRY(ShowTeaching(*status, pipeline.clock().Now()));
    *shown = Shown::kTeaching;
  }
  return Status::Ok();
}

}  // namespace

Status RunFrameLoop(drivers::Camera& camera, drivers::StatusOutput* status, Pipeline& pipeline,
                    RouteDbWriter* route, FrameSink* sink, const LoopOptions& options,
                    LoopSummary* summary, drivers::AttitudeSource* attitude) {
  if (options.mode == LoopMode::kTeach && route == nullptr)
    return Status::Error(StatusCode::kInternal, "teach without a route database");
  const Clock& clock = pipeline.clock();
  LatencyTable& latency = pipeline.latency();
  LoopSummary s;
  // The caller's summary is written on every way out, the SKYLOC_TRY returns of a failed
  // write included: a teach that dies at frame 40 still says it ran 40 frames.
  struct PublishSummary {
    const LoopSummary& from;
    LoopSummary* to;
    ~PublishSummary() { *to = from; }
  } publish{s, summary};
  Retries retries;
  Nanoseconds first_timestamp{-1};
  Nanoseconds loop_start = clock.Now();
  std::uint64_t last_sequence = 0;
  bool have_sequence = false;
  FrameAttitudes attitudes;
  Shown shown = Shown::kNothing;  // what the caller left on the lines is theirs

  while (!StopRequested() && (options.max_frames == 0 || s.frames < options.max_frames)) {
    PrintReportIfAsked(latency, options, s.frames);
    if (options.button != nullptr && status != nullptr) {
      SKYLOC_TRY_ASSIGN(s.button_pressed, ButtonPressed(*status, *options.button, clock));
      if (s.button_pressed)
        break;
    }
    const Nanoseconds t0 = clock.Now();
    Status lines_failed;
    Result<drivers::Frame> captured = CaptureMovingLines(
        camera, status, shown, clock, t0 + options.capture_timeout, &lines_failed);
    const Nanoseconds t1 = clock.Now();
    SKYLOC_TRY(lines_failed);
    if (!captured.ok()) {
      const AfterCaptureError after = OnCaptureError(captured.status().code(), t0, t1, options,
                                                     status, pipeline, &shown, &retries, &s);
      if (after == AfterCaptureError::kEnd)
        break;
      if (after == AfterCaptureError::kRetry)
        continue;
      // Every Capture() error names its camera (drivers/camera.h, checked by the camera
      // compliance test), so the message already says which device failed.
      return captured.status();
    }
    retries = Retries{};
    latency.Record(pipeline.stages().capture, t1 - t0);
    const drivers::Frame& frame = *captured;

    if (options.paced) {
      if (first_timestamp.count() < 0) {
        first_timestamp = frame.timestamp;
        loop_start = t1;
      }
      const Nanoseconds due = loop_start + (frame.timestamp - first_timestamp);
      SKYLOC_TRY(SleepMovingLines(status, shown, clock, due));
    }
    // A jump in the sequence numbers (dropped frames) is fine for SeqSLAM's velocity
    // band up to a point; a long gap breaks the sequence: start it again.
    if (have_sequence && frame.sequence > last_sequence + 10)
      pipeline.ResetTracking();
    last_sequence = frame.sequence;
    have_sequence = true;

    FrameResult result;
    result.frame = frame.sequence;
    result.timestamp = frame.timestamp;
    dsp::Attitude frame_attitude;
    const dsp::Attitude* attitude_used =
        attitude != nullptr && pipeline.uses_attitude()
            ? attitudes.At(*attitude, frame, &frame_attitude, &s.attitude_missing)
            : nullptr;
    if (options.recorder != nullptr)
      (void)options.recorder->Submit(frame, attitude_used);  // dropped frames are counted
    if (options.mode == LoopMode::kRecord || options.mode == LoopMode::kWaitForButton) {
      result.matched = false;  // the recorder has the frame; nothing else to do
    } else if (options.mode == LoopMode::kTeach) {
      SKYLOC_TRY(TeachFrame(frame, attitude_used, options.show_teaching, status, pipeline, *route,
                            &result, &shown));
    } else {
      Status st = pipeline.Localise(frame, &result, attitude_used);
      if (!st.ok()) {
        // A frame the descriptor rejects (wrong size from a misbehaving driver) is
        // skipped like a corrupt capture; the next frame may be fine.
        if (options.recorded || ++retries.errors_in_a_row >= options.max_consecutive_errors) {
          return st;
        }
        ++s.capture_errors;
        continue;
      }
      StageTimer timer(latency, pipeline.stages().output, clock);
      if (status != nullptr) {
        SKYLOC_TRY(status->Show(result.state, result.confidence, clock.Now()));
        shown = Shown::kState;
      }
    }
    const Nanoseconds done = clock.Now();
    result.latency = done - t1;
    latency.Record(pipeline.stages().total, done - t1);
    ++s.state_frames[static_cast<int>(result.state)];
    ++s.frames;
    if (!result.sky_contrast)
      ++s.frames_without_contrast;
    if (sink != nullptr)
      sink->OnFrame(options.mode, result, route != nullptr ? route->frames_appended() : 0);
  }
  s.stopped = StopRequested();
  return Status::Ok();
}

}  // namespace skyloc::firmware
