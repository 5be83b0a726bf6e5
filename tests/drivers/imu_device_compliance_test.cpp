// One compliance suite for every ImuDevice implementation: the same cases run against the
// simulated IMU (unpaced and paced by a manual clock), the IIO driver over a fake sysfs
// tree with a FIFO for the character device (buffer and polling), and the IIO driver on a
// real device named by SKYLOC_TEST_IIO_DEVICE (buffer, and polling), which the HIL harness
// sets inside the VM for the kernel's iio_dummy patched into a 6-axis IMU. Real instances
// are SKIPPED with the reason when no device is named.
//
// Each instance is a still, level IMU: accelerometer (0, 0, +1 g), a small gyro bias that
// differs on every axis.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fake_iio_device.h"
#include "skyloc/drivers/iio_imu.h"
#include "skyloc/drivers/imu_device.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/clock.h"
#include "support/scratch_dir.h"
#include "support/status_assertions.h"
#include "test_env.h"

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

Nanoseconds Monotonic() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return Nanoseconds(static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec);
}

Nanoseconds ThreadCpu() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return Nanoseconds(static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec);
}

// Owns an IMU and what it needs; the hooks let the generic cases drive each kind.
class ImuUnderTest {
 public:
  virtual ~ImuUnderTest() = default;
  virtual ImuDevice& imu() = 0;
  // Makes about `n` more samples available (a fake device writes them; real ones and the
  // unpaced simulation have them anyway).
  virtual void Produce(int n) { (void)n; }
  // Stops the flow of samples for good (until Stop()/Start()); false when the device
  // cannot be stalled (sysfs polling produces a sample every period).
  virtual bool Stall() { return false; }
  // The device goes away / comes back. Empty string: done; else why it cannot be done.
  virtual std::string Vanish() = 0;
  virtual std::string Revive() = 0;
  // Lets `d` of the device's time pass (a ManualClock moves; real time is slept).
  virtual void Wait(Nanoseconds d) { std::this_thread::sleep_for(d); }
};

struct ImuCase {
  const char* name;
  std::unique_ptr<ImuUnderTest> (*make)(std::string* skip);
  bool monotonic_clock_timestamps;  // timestamps are CLOCK_MONOTONIC times near now
  bool blocks;                      // Read() waits out its timeout (not the simulation)
};

// --- the simulated IMU ---
std::vector<dsp::ImuSample> LevelStill(int n, double rate_hz) {
  std::vector<dsp::ImuSample> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    v[static_cast<std::size_t>(i)].timestamp_ns =
        1'000'000'000 + static_cast<std::int64_t>(i * 1e9 / rate_hz);
    v[static_cast<std::size_t>(i)].accel_mps2 = {0.0f, 0.0f,
                                                 static_cast<float>(dsp::kStandardGravity)};
    v[static_cast<std::size_t>(i)].gyro_radps = {0.01f, -0.02f, 0.03f};
  }
  return v;
}

class SimUnderTest final : public ImuUnderTest {
 public:
  explicit SimUnderTest(bool paced)
      : samples_(LevelStill(5000, 200.0)),
        paced_(paced),
        imu_(SimulatedImuConfig{"sim:compliance", 200.0, true, {}}, samples_,
             paced ? &clock_ : nullptr) {}
  ImuDevice& imu() override { return imu_; }
  void Produce(int n) override {
    if (paced_)
      clock_.Advance(milliseconds(5) * n);
  }
  bool Stall() override {
    return imu_.InjectFault({ImuFault::Kind::kStall, Next(), 1'000'000}).ok();
  }
  std::string Vanish() override {
    Status s = imu_.InjectFault({ImuFault::Kind::kVanish, Next(), 1});
    return s.ok() ? "" : s.message();
  }
  std::string Revive() override {
    imu_.ClearFaults();
    return "";
  }
  void Wait(Nanoseconds d) override {
    if (paced_)
      clock_.Advance(d);
    else
      ImuUnderTest::Wait(d);
  }

 private:
  // The index of the next sample the IMU will deliver (nothing is dropped here).
  std::uint64_t Next() const { return imu_.counters().samples; }
  std::vector<dsp::ImuSample> samples_;
  bool paced_;
  ManualClock clock_{seconds(50)};
  SimulatedImu imu_;
};

std::unique_ptr<ImuUnderTest> MakeSim(std::string*) {
  return std::make_unique<SimUnderTest>(false);
}
std::unique_ptr<ImuUnderTest> MakeSimPaced(std::string*) {
  return std::make_unique<SimUnderTest>(true);
}

// --- IioImu over the fake tree ---
class IioFakeUnderTest final : public ImuUnderTest {
 public:
  explicit IioFakeUnderTest(bool buffer)
      : scratch_("imu_iio_fake_"),
        fake_(scratch_.path(), testing::FakeIioDevice::Options{"fake_imu", 2, buffer, true}),
        imu_(Config(buffer)) {}
  ImuDevice& imu() override { return imu_; }
  void Produce(int n) override { fake_.Produce(n); }
  bool Stall() override { return imu_.buffered(); }  // nothing is produced unless asked
  std::string Vanish() override {
    fake_.Vanish();
    return "";
  }
  std::string Revive() override {
    fake_.Revive();
    return "";
  }

 private:
  IioImuConfig Config(bool buffer) const {
    IioImuConfig c;
    std::snprintf(c.device, sizeof(c.device), "fake_imu");
    std::snprintf(c.trigger, sizeof(c.trigger), "faketrig");
    std::snprintf(c.sysfs_root, sizeof(c.sysfs_root), "%s", fake_.sysfs_root().c_str());
    std::snprintf(c.dev_root, sizeof(c.dev_root), "%s", fake_.dev_root().c_str());
    c.sample_rate_hz = 1000.0;  // the fake and polling run in real time: 1 ms a sample
    c.mode = buffer ? IioImuConfig::Mode::kBuffer : IioImuConfig::Mode::kPolling;
    return c;
  }
  skyloc::testing::ScratchDir scratch_;
  testing::FakeIioDevice fake_;
  IioImu imu_;
};

std::unique_ptr<ImuUnderTest> MakeIioFakeBuffer(std::string*) {
  return std::make_unique<IioFakeUnderTest>(true);
}
std::unique_ptr<ImuUnderTest> MakeIioFakePolling(std::string*) {
  return std::make_unique<IioFakeUnderTest>(false);
}

// --- IioImu on a real device ---
bool WriteFile(const std::string& path, const char* text) {
  std::ofstream f(path);
  f << text;
  f.flush();
  return static_cast<bool>(f);
}

class IioRealUnderTest final : public ImuUnderTest {
 public:
  explicit IioRealUnderTest(const IioImuConfig& c) : config_(c), imu_(c) {}
  ImuDevice& imu() override { return imu_; }
  bool Stall() override {
    // An hrtimer trigger slowed to one tick in 1000 s (DoStart() sets the rate back).
    const char* trigger = testing::Env("SKYLOC_TEST_IIO_TRIGGER");
    if (!imu_.buffered() || trigger == nullptr)
      return false;
    for (int n = 0; n < 64; ++n) {
      const std::string dir = std::string(config_.sysfs_root) + "/trigger" + std::to_string(n);
      std::ifstream name_file(dir + "/name");
      std::string name;
      if (std::getline(name_file, name) && name == trigger)
        return WriteFile(dir + "/sampling_frequency", "0.001");
    }
    return false;
  }
  std::string Vanish() override {
    const char* dir = testing::Env("SKYLOC_TEST_IIO_CONFIGFS");
    if (dir == nullptr)
      return "SKYLOC_TEST_IIO_CONFIGFS (the device's configfs folder) is not set";
    return ::rmdir(dir) == 0 ? "" : std::string("rmdir ") + dir + ": " + std::strerror(errno);
  }
  std::string Revive() override {
    const char* dir = testing::Env("SKYLOC_TEST_IIO_CONFIGFS");
    if (dir == nullptr)
      return "SKYLOC_TEST_IIO_CONFIGFS is not set";
    if (::access(dir, F_OK) == 0)
      return "";  // still there
    return ::mkdir(dir, 0755) == 0 ? "" : std::string("mkdir ") + dir + ": " + std::strerror(errno);
  }

 private:
  IioImuConfig config_;
  IioImu imu_;
};

std::unique_ptr<ImuUnderTest> MakeIio(std::string* skip, IioImuConfig::Mode mode) {
  const char* device = testing::Env("SKYLOC_TEST_IIO_DEVICE");
  if (device == nullptr) {
    *skip =
        "no IIO IMU: set SKYLOC_TEST_IIO_DEVICE=/dev/iio:deviceN or its name (the HIL VM "
        "does, with the patched iio_dummy), SKYLOC_TEST_IIO_TRIGGER and SKYLOC_TEST_IIO_CONFIGFS";
    return nullptr;
  }
  IioImuConfig c;
  std::snprintf(c.device, sizeof(c.device), "%s", device);
  if (const char* trigger = testing::Env("SKYLOC_TEST_IIO_TRIGGER"))
    std::snprintf(c.trigger, sizeof(c.trigger), "%s", trigger);
  c.mode = mode;
  c.sample_rate_hz = mode == IioImuConfig::Mode::kPolling ? 50.0 : 100.0;
  return std::make_unique<IioRealUnderTest>(c);
}
std::unique_ptr<ImuUnderTest> MakeIioBuffer(std::string* skip) {
  return MakeIio(skip, IioImuConfig::Mode::kBuffer);
}
std::unique_ptr<ImuUnderTest> MakeIioPolling(std::string* skip) {
  return MakeIio(skip, IioImuConfig::Mode::kPolling);
}

const ImuCase kImuCases[] = {
    {"Simulated", MakeSim, false, false},
    {"SimulatedPaced", MakeSimPaced, false, false},
    {"IioFakeBuffer", MakeIioFakeBuffer, true, true},
    {"IioFakePolling", MakeIioFakePolling, true, true},
    {"Iio", MakeIioBuffer, true, true},
    {"IioPolling", MakeIioPolling, true, true},
};

constexpr Nanoseconds kReadTimeout = seconds(2);

class ImuCompliance : public ::testing::TestWithParam<ImuCase> {
 protected:
  void SetUp() override {
    std::string skip;
    under_ = GetParam().make(&skip);
    if (!under_)
      GTEST_SKIP() << skip;
  }
  ImuDevice& imu() { return under_->imu(); }

  // Reads `n` samples (several Read() calls), checking each batch.
  std::vector<dsp::ImuSample> ReadSamples(int n) {
    std::vector<dsp::ImuSample> got;
    std::array<dsp::ImuSample, 16> buf{};
    for (int calls = 0; static_cast<int>(got.size()) < n && calls < 10 * n; ++calls) {
      under_->Produce(static_cast<int>(buf.size()));
      Result<std::size_t> r = imu().Read(buf, kReadTimeout);
      if (!r.ok()) {
        ADD_FAILURE() << "after " << got.size() << " samples: " << r.status().message();
        return got;
      }
      EXPECT_GE(*r, 1u);
      EXPECT_LE(*r, buf.size());
      got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*r));
    }
    EXPECT_GE(static_cast<int>(got.size()), n);
    return got;
  }

  static std::array<double, 6> Mean(const std::vector<dsp::ImuSample>& v) {
    std::array<double, 6> m{};
    for (const dsp::ImuSample& s : v) {
      for (std::size_t i = 0; i < 3; ++i) {
        m[i] += static_cast<double>(s.accel_mps2[i]);
        m[3 + i] += static_cast<double>(s.gyro_radps[i]);
      }
    }
    for (double& x : m)
      x /= v.empty() ? 1.0 : static_cast<double>(v.size());
    return m;
  }

  // Takes the streaming device away and reads until Read() fails (samples read before it
  // went may still be delivered first): that read's status.
  Status VanishAndReadUntilFailure() {
    const std::string why = under_->Vanish();
    EXPECT_TRUE(why.empty()) << why;
    std::array<dsp::ImuSample, 16> buf{};
    Result<std::size_t> r = imu().Read(buf, milliseconds(300));
    for (int i = 0; i < 1000 && r.ok(); ++i)
      r = imu().Read(buf, milliseconds(300));
    return r.status();
  }

  std::unique_ptr<ImuUnderTest> under_;
};

TEST_P(ImuCompliance, OpenStartReadStopClose) {
  ASSERT_OK(imu().Open());
  EXPECT_EQ(imu().state(), ImuDevice::State::kOpen);
  ASSERT_OK(imu().Start());
  EXPECT_EQ(imu().state(), ImuDevice::State::kStreaming);
  const std::vector<dsp::ImuSample> got = ReadSamples(10);
  EXPECT_GE(imu().counters().samples, got.size());
  EXPECT_GT(imu().info().sample_rate_hz, 0.0);
  EXPECT_NE(imu().info().name[0], '\0');
  EXPECT_NE(imu().info().source[0], '\0');
  std::printf("  %s: %s, %.1f Hz%s\n", imu().info().name, imu().info().source,
              imu().info().sample_rate_hz, imu().info().has_gyro ? "" : ", no gyroscope");
  imu().Stop();
  EXPECT_EQ(imu().state(), ImuDevice::State::kOpen);
  imu().Close();
  EXPECT_EQ(imu().state(), ImuDevice::State::kClosed);
}

TEST_P(ImuCompliance, CallsInTheWrongStateAreRefused) {
  std::array<dsp::ImuSample, 4> buf{};
  Result<std::size_t> r = imu().Read(buf, milliseconds(1));
  EXPECT_EQ(r.status().code(), StatusCode::kFailedPrecondition) << r.status().message();
  EXPECT_EQ(imu().Start().code(), StatusCode::kFailedPrecondition);
  ASSERT_OK(imu().Open());
  EXPECT_EQ(imu().Open().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(imu().SetMounting({180, 0, 0}).code(), StatusCode::kFailedPrecondition);
  r = imu().Read(buf, milliseconds(1));
  EXPECT_EQ(r.status().code(), StatusCode::kFailedPrecondition);
  ASSERT_OK(imu().Start());
  EXPECT_EQ(imu().Start().code(), StatusCode::kFailedPrecondition);
  r = imu().Read(std::span<dsp::ImuSample>(), milliseconds(1));
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(imu().counters().errors, 3u);
  imu().Close();  // stops first
  EXPECT_EQ(imu().state(), ImuDevice::State::kClosed);
  imu().Stop();  // no-ops
  imu().Close();
  EXPECT_EQ(imu().state(), ImuDevice::State::kClosed);
  EXPECT_EQ(imu().SetMounting({0, std::nan(""), 0}).code(), StatusCode::kInvalidArgument);
}

TEST_P(ImuCompliance, TimestampsIncreaseAtTheReportedRate) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  const std::vector<dsp::ImuSample> got = ReadSamples(40);
  const Nanoseconds now = Monotonic();
  ASSERT_GE(got.size(), 40u);
  for (std::size_t i = 1; i < got.size(); ++i)
    ASSERT_GT(got[i].timestamp_ns, got[i - 1].timestamp_ns) << "sample " << i;
  if (GetParam().monotonic_clock_timestamps) {
    EXPECT_LE(got.back().timestamp_ns, (now + milliseconds(5)).count())
        << "not CLOCK_MONOTONIC (ahead of it)";
    EXPECT_GE(got.back().timestamp_ns, (now - seconds(10)).count())
        << "not CLOCK_MONOTONIC (far behind it)";
  }
  // Samples the device reports as lost (polling ticks missed while the test was not
  // reading, gaps in a starved producer's timestamps) are intervals too: without them a
  // loaded machine would fail this check for the machine's sake, not the driver's.
  const double intervals =
      static_cast<double>(got.size() - 1) + static_cast<double>(imu().counters().dropped);
  const double mean_interval =
      static_cast<double>(got.back().timestamp_ns - got.front().timestamp_ns) / intervals;
  const double period = 1e9 / imu().info().sample_rate_hz;
  EXPECT_GT(mean_interval, 0.5 * period);
  EXPECT_LT(mean_interval, 2.0 * period) << imu().counters().dropped << " dropped";
}

TEST_P(ImuCompliance, LevelAndStillReadsOneGUp) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  const std::array<double, 6> m = Mean(ReadSamples(20));
  EXPECT_NEAR(m[0], 0.0, 0.15);
  EXPECT_NEAR(m[1], 0.0, 0.15);
  EXPECT_NEAR(m[2], dsp::kStandardGravity, 0.15);
  if (imu().info().has_gyro) {
    for (std::size_t i = 3; i < 6; ++i)
      EXPECT_NEAR(m[i], 0.0, 0.1) << "gyro axis " << i - 3;
  }
}

TEST_P(ImuCompliance, MountingRotatesAccelAndGyro) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  const std::array<double, 6> raw = Mean(ReadSamples(10));
  imu().Close();

  Result<ImuMounting> remap = ImuMountingFromAxes("y,-x,z");
  ASSERT_TRUE(remap.ok()) << remap.status().message();
  const ImuMounting mountings[] = {{180, 0, 0}, {0, 90, 0}, {0, 0, 90}, {30, -20, 45}, *remap};
  for (const ImuMounting& m : mountings) {
    SCOPED_TRACE(::testing::Message() << "mounting roll " << m.roll_deg << " pitch " << m.pitch_deg
                                      << " yaw " << m.yaw_deg);
    ASSERT_OK(imu().SetMounting(m));
    ASSERT_OK(imu().Open());
    ASSERT_OK(imu().Start());
    const std::array<double, 6> got = Mean(ReadSamples(10));
    imu().Close();
    Result<std::array<double, 9>> r = ImuMountingMatrix(m);
    ASSERT_TRUE(r.ok());
    for (std::size_t v = 0; v < 2; ++v) {
      for (std::size_t i = 0; i < 3; ++i) {
        const double want = (*r)[3 * i] * raw[3 * v] + (*r)[3 * i + 1] * raw[3 * v + 1] +
                            (*r)[3 * i + 2] * raw[3 * v + 2];
        EXPECT_NEAR(got[3 * v + i], want, v == 0 ? 0.05 : 0.003)
            << (v == 0 ? "accel" : "gyro") << " axis " << i;
      }
    }
  }
  // Upside down, gravity reads -1 g on z.
  ASSERT_OK(imu().SetMounting({180, 0, 0}));
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  EXPECT_NEAR(Mean(ReadSamples(5))[2], -dsp::kStandardGravity, 0.15);
}

TEST_P(ImuCompliance, ReadTimesOutWhenNoSampleComes) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  ReadSamples(3);
  std::array<dsp::ImuSample, 16> buf{};
  if (!under_->Stall()) {
    // Sysfs polling: a sample is due every period, so a zero timeout right after one has
    // been read finds none yet. On a slow machine (the emulated arm64 VM) the next period
    // may already have come by the time Read() runs, so it gets a few tries: a driver that
    // never times out still fails all of them.
    Result<std::size_t> r = imu().Read(buf, Nanoseconds(0));
    for (int i = 0; i < 20 && r.ok(); ++i)
      r = imu().Read(buf, Nanoseconds(0));
    EXPECT_EQ(r.status().code(), StatusCode::kDeadlineExceeded) << r.status().message();
    return;
  }
  // Whatever was queued before the stall is drained first.
  Result<std::size_t> r = imu().Read(buf, milliseconds(50));
  for (int i = 0; i < 1000 && r.ok(); ++i)
    r = imu().Read(buf, milliseconds(50));
  const std::uint64_t errors = imu().counters().errors;
  const Nanoseconds t0 = Monotonic();
  const Nanoseconds cpu0 = ThreadCpu();
  r = imu().Read(buf, milliseconds(200));
  const Nanoseconds waited = Monotonic() - t0;
  const Nanoseconds cpu = ThreadCpu() - cpu0;
  EXPECT_EQ(r.status().code(), StatusCode::kDeadlineExceeded) << r.status().message();
  EXPECT_EQ(imu().counters().errors, errors) << "a time-out is not an error";
  if (GetParam().blocks) {
    EXPECT_GE(waited, milliseconds(195));
    EXPECT_LT(waited, seconds(2));
    EXPECT_LT(cpu, milliseconds(50)) << "Read() spun instead of sleeping in poll()";
  }
  // A restart brings the samples back.
  imu().Stop();
  imu().Close();
  ASSERT_TRUE(under_->Revive().empty());
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  ReadSamples(3);
}

TEST_P(ImuCompliance, VanishedDeviceIsUnavailableThenReopens) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  ReadSamples(5);
  const Status gone = VanishAndReadUntilFailure();
  EXPECT_EQ(gone.code(), StatusCode::kUnavailable) << gone.message();
  EXPECT_NE(std::string(gone.message()).find(imu().info().name), std::string::npos)
      << "the message names the IMU: " << gone.message();
  std::printf("  vanished: %s\n", gone.message());
  std::array<dsp::ImuSample, 16> buf{};
  Result<std::size_t> r = imu().Read(buf, milliseconds(10));
  EXPECT_EQ(r.status().code(), StatusCode::kUnavailable) << "stays gone: " << r.status().message();
  imu().Close();

  const std::string back = under_->Revive();
  ASSERT_TRUE(back.empty()) << back;
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  const std::array<double, 6> m = Mean(ReadSamples(5));
  EXPECT_NEAR(m[2], dsp::kStandardGravity, 0.15);
}

// A device that goes away and comes back heals without a call from the caller: Read()
// reopens it on the camera's backoff and the samples flow again (ImuDevice, "Healing").
TEST_P(ImuCompliance, AGoneDeviceReopensItselfOnceItIsBack) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  ReadSamples(5);
  const Status gone = VanishAndReadUntilFailure();
  ASSERT_EQ(gone.code(), StatusCode::kUnavailable) << gone.message();
  std::array<dsp::ImuSample, 16> buf{};
  Result<std::size_t> r = gone;
  EXPECT_EQ(imu().counters().outages, 1u);
  EXPECT_EQ(imu().counters().reopens, 0u);
  const std::string back = under_->Revive();
  ASSERT_TRUE(back.empty()) << back;
  // The attempts come at most backoff_max (500 ms) apart: 40 reads 100 ms apart see one.
  for (int i = 0; i < 40; ++i) {
    under_->Wait(milliseconds(100));
    under_->Produce(static_cast<int>(buf.size()));
    r = imu().Read(buf, milliseconds(100));
    if (r.ok())
      break;
  }
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(imu().counters().reopens, 1u);
  EXPECT_EQ(imu().counters().outages, 1u);
  EXPECT_EQ(imu().state(), ImuDevice::State::kStreaming);
  EXPECT_NEAR(Mean(ReadSamples(5))[2], dsp::kStandardGravity, 0.15);
}

TEST_P(ImuCompliance, ReopenAndRestart) {
  for (int round = 0; round < 2; ++round) {
    ASSERT_OK(imu().Open());
    for (int start = 0; start < 2; ++start) {
      ASSERT_OK(imu().Start());
      ReadSamples(5);
      imu().Stop();
    }
    imu().Close();
  }
  EXPECT_GE(imu().counters().samples, 20u);
}

TEST_P(ImuCompliance, ReadDoesNotAllocate) {
  ASSERT_OK(imu().Open());
  ASSERT_OK(imu().Start());
  ASSERT_TRUE(AllocationCounterActive());
  ReadSamples(3);
  std::array<dsp::ImuSample, 16> buf{};
  for (int i = 0; i < 5; ++i) {
    under_->Produce(4);
    const AllocationScope scope;
    Result<std::size_t> r = imu().Read(buf, kReadTimeout);
    const std::uint64_t allocations = scope.allocations();
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(allocations, 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(AllImus, ImuCompliance, ::testing::ValuesIn(kImuCases),
                         [](const ::testing::TestParamInfo<ImuCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

}  // namespace
}  // namespace skyloc::drivers
