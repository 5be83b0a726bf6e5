#include "firmware/frame_recorder.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <string>
#include <thread>

#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/platform/alloc_counter.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

constexpr int kWidth = 64, kHeight = 48;

// Frame i: a noisy grey pattern of its own (PNG cannot shrink it much: ~3.1 KB), or a flat
// grey (`flat`: ~100 bytes), at i x 100 ms.
struct TestFrame {
  std::vector<std::uint8_t> pixels;
  drivers::Frame frame;
};

TestFrame MakeFrame(int i, bool flat = false) {
  TestFrame t;
  t.pixels.resize(static_cast<std::size_t>(kWidth) * kHeight);
  std::uint32_t x = 2654435761u * static_cast<std::uint32_t>(i + 1);
  for (auto& p : t.pixels) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    p = flat ? static_cast<std::uint8_t>(i) : static_cast<std::uint8_t>(x);
  }
  t.frame.image = {t.pixels.data(), kWidth, kHeight, kWidth, dsp::PixelFormat::kGrey8};
  t.frame.sequence = static_cast<std::uint64_t>(i);
  t.frame.timestamp = std::chrono::milliseconds(5000 + 100 * i);
  return t;
}

drivers::CameraInfo Info() {
  drivers::CameraInfo info;
  info.width = kWidth;
  info.height = kHeight;
  info.format = dsp::PixelFormat::kGrey8;
  return info;
}

void WaitWritten(const FrameRecorder& r, std::uint64_t n) {
  for (int k = 0; k < 5000 && r.counters().written < n && !r.failed(); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

TEST(FrameRecorder, WritesADatasetThatReplayReadsBackExactly) {
  skyloc::testing::ScratchDir scratch("skyloc_recorder_");
  FrameRecorderOptions o;
  o.dir = scratch.path() + "/run";
  o.camera_toml = "[image]\nwidth = 64\nheight = 48\n";
  o.with_attitude = true;
  FrameRecorder r;
  ASSERT_TRUE(r.Open(o, Info()).ok());
  for (int i = 0; i < 6; ++i) {
    const TestFrame t = MakeFrame(i);
    const dsp::Attitude a = dsp::AttitudeFromRollPitch(0, 2.0 * i, -1.5 * i);
    ASSERT_TRUE(r.Submit(t.frame, i == 3 ? nullptr : &a));
    WaitWritten(r, static_cast<std::uint64_t>(i + 1));
  }
  ASSERT_TRUE(r.Close().ok());
  EXPECT_EQ(r.counters().written, 6u);
  EXPECT_EQ(r.counters().dropped, 0u);
  EXPECT_EQ(r.counters().without_attitude, 1u);

  Result<drivers::Dataset> ds = drivers::ReadDataset(o.dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_EQ(ds->frames.size(), 6u);
  EXPECT_TRUE(ds->has_attitude);
  EXPECT_FALSE(ds->camera_toml.empty());
  for (int i = 0; i < 6; ++i) {
    const auto& f = ds->frames[static_cast<std::size_t>(i)];
    EXPECT_NEAR(f.timestamp_s, 0.1 * i, 1e-6);  // seconds since the first frame
    ASSERT_TRUE(f.attitude.has_value());
    EXPECT_DOUBLE_EQ(f.attitude->roll_deg, i == 3 ? 0.0 : 2.0 * i);
    Result<drivers::OwnedImage> image =
        drivers::LoadImage(ds->FramePath(static_cast<std::size_t>(i)).c_str());
    ASSERT_TRUE(image.ok());
    const TestFrame t = MakeFrame(i);
    EXPECT_EQ(std::memcmp(image->view().data, t.pixels.data(), t.pixels.size()), 0) << i;
  }
}

TEST(FrameRecorder, DropsAndCountsFramesWhenEverySlotIsBusy) {
  skyloc::testing::ScratchDir scratch("skyloc_recorder_");
  FrameRecorderOptions o;
  o.dir = scratch.path() + "/run";
  o.slots = 2;
  o.start_paused = true;  // the disk "stalls": nothing is written until Resume()
  FrameRecorder r;
  ASSERT_TRUE(r.Open(o, Info()).ok());
  int queued = 0;
  for (int i = 0; i < 5; ++i)
    queued += r.Submit(MakeFrame(i).frame, nullptr) ? 1 : 0;
  EXPECT_EQ(queued, 2);
  EXPECT_EQ(r.counters().dropped, 3u);
  r.Resume();
  ASSERT_TRUE(r.Close().ok());
  EXPECT_EQ(r.counters().written, 2u);
  Result<drivers::Dataset> ds = drivers::ReadDataset(o.dir);
  ASSERT_TRUE(ds.ok());
  EXPECT_EQ(ds->frames.size(), 2u);
}

TEST(FrameRecorder, SubmitAllocatesNothing) {
  skyloc::testing::ScratchDir scratch("skyloc_recorder_");
  FrameRecorderOptions o;
  o.dir = scratch.path() + "/run";
  o.start_paused = true;  // the writer thread (which allocates) stays idle meanwhile
  FrameRecorder r;
  ASSERT_TRUE(r.Open(o, Info()).ok());
  const TestFrame a = MakeFrame(0), b = MakeFrame(1);
  const dsp::Attitude level;
  AllocationScope scope;
  EXPECT_TRUE(r.Submit(a.frame, &level));
  EXPECT_TRUE(r.Submit(b.frame, nullptr));
  EXPECT_EQ(scope.allocations(), 0u);
  r.Resume();
  EXPECT_TRUE(r.Close().ok());
}

TEST(FrameRecorder, RefusesAFolderThatHoldsARecording) {
  skyloc::testing::ScratchDir scratch("skyloc_recorder_");
  FrameRecorderOptions o;
  o.dir = scratch.path() + "/run";
  {
    drivers::DatasetWriter w;
    ASSERT_TRUE(w.Open(o.dir, false).ok());
  }
  FrameRecorder r;
  const Status s = r.Open(o, Info());
  EXPECT_EQ(s.code(), StatusCode::kAlreadyExists);
  EXPECT_NE(std::string(s.message()).find("already exists"), std::string::npos) << s.message();
}

// A full disk (RLIMIT_FSIZE: no file may grow past the limit) stops the recording with its
// error while Submit goes on being refused quietly; the frames written before it are a
// valid dataset. Two flat frames fit, the first noisy one does not.
TEST(FrameRecorder, AFullDiskStopsTheRecordingAndKeepsTheFramesBefore) {
#if defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "ThreadSanitizer cannot start threads in a forked child (its own thread makes "
                  "every fork multi-threaded); the host and asan builds run this test";
#endif
  skyloc::testing::ScratchDir scratch("skyloc_recorder_");
  const std::string dir = scratch.path() + "/run";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);    // EFBIG instead of death, as skyloc's handlers set it
    const rlimit lim{2500, 2500};  // one 64x48 noise frame compresses to ~3.1 KB
    if (::setrlimit(RLIMIT_FSIZE, &lim) != 0)
      ::_exit(2);
    FrameRecorderOptions o;
    o.dir = dir;
    FrameRecorder r;
    if (!r.Open(o, Info()).ok())
      ::_exit(3);
    for (int i = 0; i < 5; ++i) {
      (void)r.Submit(MakeFrame(i, i < 2).frame, nullptr);
      WaitWritten(r, static_cast<std::uint64_t>(i + 1));
    }
    const Status s = r.Close();
    if (s.ok() || !r.failed())
      ::_exit(4);
    if (std::string(s.message()).find("File too large") == std::string::npos)
      ::_exit(5);
    ::_exit(r.counters().written == 2 && r.counters().lost_after_error == 2 ? 0 : 6);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0);
  // The frame that did not fit left no row and no partial image.
  Result<drivers::Dataset> ds = drivers::ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_EQ(ds->frames.size(), 2u);
  for (std::size_t i = 0; i < ds->frames.size(); ++i)
    EXPECT_TRUE(drivers::LoadImage(ds->FramePath(i).c_str()).ok());
}

}  // namespace
}  // namespace skyloc::firmware
