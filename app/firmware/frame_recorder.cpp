#include "firmware/frame_recorder.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "skyloc/drivers/image_file.h"

namespace skyloc::firmware {

FrameRecorder::~FrameRecorder() {
  (void)Close();
}

Status FrameRecorder::Open(const FrameRecorderOptions& options, const drivers::CameraInfo& info) {
  if (is_open())
    return Status::Error(StatusCode::kFailedPrecondition, "recording to %s: already open",
                         options_.dir.c_str());
  if (options.slots < 2 || options.slots > 64)
    return Status::Error(StatusCode::kInvalidArgument, "recording: %d frame slots; give 2..64",
                         options.slots);
  if (info.width <= 0 || info.height <= 0)
    return Status::Error(StatusCode::kInvalidArgument,
                         "recording to %s: the camera has not said its frame size (open it first)",
                         options.dir.c_str());
  options_ = options;
  info_ = info;
  SKYLOC_TRY(writer_.Open(options.dir, options.with_attitude
                                           ? drivers::DatasetWriter::Columns::kAttitude
                                           : drivers::DatasetWriter::Columns::kNone));
  if (!options.camera_toml.empty()) {
    const std::string path = writer_.dir() + "/camera.toml";
    std::FILE* f = std::fopen(path.c_str(), "wx");
    if (f == nullptr) {
      const int saved = errno;
      return Status::FromErrno(saved, "recording: cannot create %s", path.c_str());
    }
    const bool ok = std::fwrite(options.camera_toml.data(), 1, options.camera_toml.size(), f) ==
                    options.camera_toml.size();
    const int saved = errno;
    if (std::fclose(f) != 0 || !ok)
      return Status::FromErrno(ok ? errno : saved, "recording: cannot write %s", path.c_str());
  }
  const dsp::ImageView shape{nullptr, info.width, info.height, 0, info.format};
  slots_.assign(static_cast<std::size_t>(options.slots), Slot{});
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    slots_[i].pixels.resize(shape.RowBytes() * static_cast<std::size_t>(info.height));
    (void)free_.TryPush(static_cast<int>(i));  // slots <= 64 = the queue's capacity
  }
  stop_.store(false);
  failed_.store(false);
  paused_.store(options.start_paused);
  written_.store(0);
  submitted_ = dropped_ = lost_after_error_ = without_attitude_ = 0;
  first_timestamp_ns_ = -1;
  error_ = Status::Ok();
  writer_thread_ = std::thread([this] { WriterLoop(); });
  return Status::Ok();
}

bool FrameRecorder::Submit(const drivers::Frame& frame, const dsp::Attitude* attitude) {
  if (!is_open())
    return false;
  ++submitted_;
  if (failed()) {
    ++lost_after_error_;
    return false;
  }
  const dsp::ImageView& image = frame.image;
  if (image.width != info_.width || image.height != info_.height || image.format != info_.format) {
    ++dropped_;  // the frame loop reports a frame of another size as a capture error
    return false;
  }
  int index = -1;
  if (!free_.TryPop(&index)) {
    ++dropped_;
    return false;
  }
  Slot& slot = slots_[static_cast<std::size_t>(index)];
  const std::size_t row = image.RowBytes();
  for (int y = 0; y < image.height; ++y)
    std::memcpy(slot.pixels.data() + static_cast<std::size_t>(y) * row, image.Row(y), row);
  if (first_timestamp_ns_ < 0)
    first_timestamp_ns_ = frame.timestamp.count();
  // Seconds since the recording's first frame, as a dataset's timestamps are.
  slot.timestamp_s = static_cast<double>(frame.timestamp.count() - first_timestamp_ns_) * 1e-9;
  slot.has_attitude = attitude != nullptr;
  if (attitude != nullptr)
    slot.attitude = *attitude;
  else if (options_.with_attitude)
    ++without_attitude_;
  (void)ready_.TryPush(index);  // never full: it holds at most the slots' indices
  return true;
}

void FrameRecorder::Resume() {
  paused_.store(false, std::memory_order_release);
}

Status FrameRecorder::WriteSlot(const Slot& slot) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", writer_.frames_written());
  const std::string path = writer_.dir() + "/frames/" + name;
  const dsp::ImageView image{slot.pixels.data(), info_.width, info_.height,
                             dsp::ImageView{nullptr, info_.width, 0, 0, info_.format}.RowBytes(),
                             info_.format};
  // SavePng writes a temporary file and renames it, so the row appended next always
  // names a complete image.
  SKYLOC_TRY(drivers::SavePng(path.c_str(), image));
  if (options_.with_attitude) {
    return writer_.AppendRow(name, slot.timestamp_s,
                             slot.has_attitude ? slot.attitude : dsp::Attitude{});
  }
  return writer_.AppendRow(name, slot.timestamp_s, std::optional<drivers::Pose>{});
}

void FrameRecorder::WriterLoop() {
  for (;;) {
    int index = -1;
    if (paused_.load(std::memory_order_acquire) || !ready_.TryPop(&index)) {
      if (stop_.load(std::memory_order_acquire) && !paused_.load() && ready_.size() == 0)
        return;
      // The queue is polled: a few milliseconds of latency cost nothing here, and the frame
      // path stays free of locks and wake-ups.
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    if (!failed()) {
      if (const Status s = WriteSlot(slots_[static_cast<std::size_t>(index)]); !s.ok()) {
        error_ = s;
        failed_.store(true, std::memory_order_release);
        std::fprintf(stderr,
                     "skyloc: recording to %s stopped: %s; the %llu frames before it are kept "
                     "(localisation goes on)\n",
                     writer_.dir().c_str(), s.message(),
                     static_cast<unsigned long long>(written_.load()));
      } else {
        written_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    (void)free_.TryPush(index);
  }
}

Status FrameRecorder::Close() {
  if (!is_open())
    return Status::Ok();
  paused_.store(false);
  stop_.store(true, std::memory_order_release);
  writer_thread_.join();
  const Status closed = writer_.Close();
  if (failed())
    return error_;
  return closed;
}

FrameRecorderCounters FrameRecorder::counters() const {
  FrameRecorderCounters c;
  c.submitted = submitted_;
  c.written = written_.load(std::memory_order_relaxed);
  c.dropped = dropped_;
  c.lost_after_error = lost_after_error_;
  c.without_attitude = without_attitude_;
  return c;
}

}  // namespace skyloc::firmware
