#include "firmware/button_teach.h"

#include <unistd.h>

#include <cstdio>
#include <cstring>

namespace skyloc::firmware {
namespace {

void Accumulate(const LoopSummary& phase, LoopSummary* total) {
  total->frames += phase.frames;
  total->capture_errors += phase.capture_errors;
  for (int i = 0; i < 3; ++i)
    total->state_frames[i] += phase.state_frames[i];
  total->attitude_missing += phase.attitude_missing;
  total->frames_without_contrast += phase.frames_without_contrast;
  total->end_of_source = phase.end_of_source;
  total->stopped = phase.stopped;
  total->button_pressed = phase.button_pressed;
}

// Teaches from now until the next press (or a signal, the end of the source, a full
// route) into path.tmp, then commits it over path. Returns the loop's fatal error, if
// any; `*committed` says whether a new route replaced the old one.
Status TeachUntilPress(const ButtonTeachSetup& setup, const LoopOptions& repeat_options,
                       ButtonDebouncer* button, LoopSummary* total, bool* committed) {
  *committed = false;
  const char* label = setup.label;
  RouteDbWriter writer;
  // Overwrite mode: an existing route is replaced only by the commit's rename (the frames
  // go to path.tmp); a new path is not a loadable route until it is committed.
  Status created = writer.Create(setup.route_path, setup.pipeline->route_settings(),
                                 setup.flush_every, /*overwrite=*/true);
  if (!created.ok()) {
    std::fprintf(stderr, "%s: teach button: could not start teaching (%s); %s\n", label,
                 created.message(),
                 setup.route->size() > 0 ? "repeating on the old route" : "waiting again");
    return Status::Ok();
  }
  std::fprintf(
      stderr, "%s: teach button pressed: teaching a new route into %s until the next press%s\n",
      label, writer.write_path(), writer.replacing() ? " (the old route is kept until then)" : "");
  char unfinished[300];
  std::snprintf(unfinished, sizeof unfinished, "%s", writer.write_path());
  LoopOptions teach = repeat_options;
  teach.mode = LoopMode::kTeach;
  teach.button = button;
  teach.show_teaching = true;
  const auto capacity = static_cast<std::uint64_t>(setup.route->capacity());
  if (teach.max_frames == 0 || teach.max_frames > capacity)
    teach.max_frames = capacity;
  setup.pipeline->ResetTracking();
  LoopSummary phase;
  const Status loop = RunFrameLoop(*setup.camera, setup.status, *setup.pipeline, &writer,
                                   setup.sink, teach, &phase, setup.attitude);
  Accumulate(phase, total);
  (void)setup.status->SafeState();
  if (!loop.ok() || writer.frames_appended() == 0) {
    // Nothing worth replacing the old route with: the writer closes uncommitted and the
    // unfinished file (path.tmp, or a new path) is removed; unlinking it while open is
    // fine, the writer's destructor closes the orphan.
    (void)::unlink(unfinished);
    std::fprintf(stderr, "%s: teach button: %s; the route at %s is unchanged\n", label,
                 loop.ok() ? "no frame was taught" : "the teach failed", setup.route_path);
    return loop;
  }
  if (!phase.button_pressed && writer.frames_appended() >= capacity) {
    std::fprintf(stderr,
                 "%s: the route is full ([capacities] route_frames = %llu): committing it\n", label,
                 static_cast<unsigned long long>(capacity));
  }
  const Status commit = writer.Commit();
  if (writer.discarded()) {
    std::fprintf(stderr,
                 "%s: teach button: no frame reached the disk (%s); the route at %s is "
                 "unchanged\n",
                 label, commit.ok() ? "none taught" : commit.message(), setup.route_path);
    return Status::Ok();
  }
  if (!writer.committed()) {
    std::fprintf(stderr,
                 "%s: teach button: the new route was NOT committed (%s); the route at %s is "
                 "unchanged, the frames are in %s ('skyloc route recover' makes it loadable)\n",
                 label, commit.message(), setup.route_path, writer.write_path());
    return Status::Ok();
  }
  *committed = true;
  std::fprintf(
      stderr, "%s: route %s: %llu frames committed%s%s\n", label, setup.route_path,
      static_cast<unsigned long long>(writer.frames_durable()),
      commit.ok() ? "" : "; the last frames did not fit: ", commit.ok() ? "" : commit.message());
  return Status::Ok();
}

}  // namespace

Status RunRepeatWithButton(const ButtonTeachSetup& setup, const LoopOptions& options,
                           ButtonDebouncer* button, ButtonTeachReport* report) {
  if (setup.status == nullptr || !setup.status->has_button())
    return Status::Error(StatusCode::kInternal, "repeat with a teach button but no button");
  const char* label = setup.label;
  LoopSummary& total = report->loop;
  for (;;) {
    const bool have_route = setup.route->size() > 0;
    LoopOptions phase_options = options;
    phase_options.button = button;
    phase_options.mode = have_route ? LoopMode::kRepeat : LoopMode::kWaitForButton;
    if (!have_route)
      SKYLOC_TRY(setup.status->SafeState());
    LoopSummary phase;
    const Status loop =
        RunFrameLoop(*setup.camera, setup.status, *setup.pipeline, nullptr,
                     have_route ? setup.sink : nullptr, phase_options, &phase, setup.attitude);
    Accumulate(phase, &total);
    SKYLOC_TRY(loop);
    if (!phase.button_pressed)
      return Status::Ok();  // a signal, the end of the source or max_frames

    bool committed = false;
    SKYLOC_TRY(TeachUntilPress(setup, options, button, &total, &committed));
    if (committed) {
      const RouteDbSettings want = setup.pipeline->route_settings();
      RouteDbLoadReport loaded;
      SKYLOC_TRY(
          LoadRouteDb(setup.route_path, &want, RouteDbLoadPolicy::kStrict, setup.route, &loaded));
      SKYLOC_TRY(setup.pipeline->SetRoute(*setup.route));
      setup.pipeline->ResetTracking();
      ++report->routes_taught;
      std::fprintf(stderr, "%s: repeating on the new route (%zu frames)\n", label,
                   setup.route->size());
    }
    if (total.stopped || total.end_of_source)
      return Status::Ok();
  }
}

}  // namespace skyloc::firmware
