// Records the frames a mode sees into a dataset folder (docs/DATASETS.md) that replay and
// eval read: `skyloc record DIR`, and `--record DIR` on teach and repeat. The frame loop
// never waits for the disk: Submit() copies the frame into one of a fixed number of slots
// allocated at Open() and hands the slot to a writer thread through a lock-free queue; when
// every slot is still being written the frame is dropped and counted. A write error (a
// full disk) stops the recording with one message on stderr while the mode goes on; the
// frames already written stay a valid dataset (each row is appended after its image).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/spsc_queue.h"
#include "skyloc/platform/status.h"

namespace skyloc::firmware {

struct FrameRecorderOptions {
  std::string dir;             // the dataset folder; refused if it already holds frames.csv
  std::string camera_toml;     // the camera file's text, written as DIR/camera.toml ("" : none)
  bool with_attitude = false;  // frames.csv gets roll_deg,pitch_deg (frames without one are 0,0
                               // and counted: an IMU outage)
  int slots = 8;               // frames in flight to the writer (2..64)
  bool start_paused = false;   // tests: the writer waits for Resume(), so drops are exact
};

struct FrameRecorderCounters {
  std::uint64_t submitted = 0;         // frames offered
  std::uint64_t written = 0;           // frames in the dataset
  std::uint64_t dropped = 0;           // no free slot (the disk slower than the camera)
  std::uint64_t lost_after_error = 0;  // offered after a write error stopped the recording
  std::uint64_t without_attitude = 0;  // with_attitude but the frame had none (written 0,0)
};

class FrameRecorder {
 public:
  FrameRecorder() = default;
  ~FrameRecorder();
  FrameRecorder(const FrameRecorder&) = delete;
  FrameRecorder& operator=(const FrameRecorder&) = delete;

  // Creates the dataset folder, allocates `slots` buffers for frames of `info`'s size and
  // format, and starts the writer thread.
  Status Open(const FrameRecorderOptions& options, const drivers::CameraInfo& info);

  // Frame path: copies the frame (and its timestamp and attitude) into a free slot and
  // queues it. Allocates nothing and never blocks. False when the frame was not queued
  // (dropped, or the recording stopped after a write error).
  bool Submit(const drivers::Frame& frame, const dsp::Attitude* attitude);

  // Writes what is queued, stops the thread and closes frames.csv. The first write error,
  // if any, naming the file (the frames before it are kept).
  Status Close();

  void Resume();  // start_paused: let the writer run
  bool is_open() const { return writer_thread_.joinable(); }
  bool failed() const { return failed_.load(std::memory_order_acquire); }
  FrameRecorderCounters counters() const;
  const std::string& dir() const { return options_.dir; }

 private:
  struct Slot {
    std::vector<std::uint8_t> pixels;
    double timestamp_s = 0;
    bool has_attitude = false;
    dsp::Attitude attitude;
  };
  static constexpr std::size_t kQueueCapacity = 64;

  void WriterLoop();
  Status WriteSlot(const Slot& slot);

  FrameRecorderOptions options_;
  drivers::CameraInfo info_;
  std::vector<Slot> slots_;
  SpscQueue<int, kQueueCapacity> ready_;  // frame path -> writer
  SpscQueue<int, kQueueCapacity> free_;   // writer -> frame path
  drivers::DatasetWriter writer_;
  std::thread writer_thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> paused_{false};
  std::atomic<bool> failed_{false};
  Status error_;  // written by the writer thread before failed_ is set
  std::int64_t first_timestamp_ns_ = -1;
  std::uint64_t submitted_ = 0, dropped_ = 0, lost_after_error_ = 0, without_attitude_ = 0;
  std::atomic<std::uint64_t> written_{0};
};

}  // namespace skyloc::firmware
