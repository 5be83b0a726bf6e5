// One suite for every StatusOutput: the simulated twin (always) and libgpiod on a real
// chip (SKYLOC_TEST_GPIOCHIP; the HIL VM provides gpio-sim). Each case runs in both line
// modes. Levels are read back independently of the output under test: from the twin's
// record, or from gpio-sim's sysfs (<chip dir>/sim_gpio<offset>/value), which shows what
// the kernel actually drives on the simulated pin.
#include <fcntl.h>
#include <glob.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <ostream>
#include <string>

#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/drivers/status_output.h"
#include "skyloc/drivers/status_pattern.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/clock.h"
#include "support/status_assertions.h"
#include "test_env.h"
#if SKYLOC_WITH_GPIOD
#include "gpio_sim.h"
#include "skyloc/drivers/gpio_status_output.h"
#endif

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;

class OutputUnderTest {
 public:
  virtual ~OutputUnderTest() = default;
  virtual StatusOutput& output() = 0;
  // The level line `i` (0..line_count-1) is driven to, read independently; an error
  // when this implementation cannot be read back (a real chip that is not gpio-sim).
  virtual Result<bool> ReadBack(std::size_t i) = 0;
  virtual bool has_button() = 0;
  virtual Status SetButton(bool pressed) = 0;
  virtual int button_fd() = 0;
  virtual Result<ButtonEvent> ReadButtonEvent() = 0;
};

// --- the simulated twin ---
class SimOutput final : public OutputUnderTest {
 public:
  explicit SimOutput(StatusLineMode mode) : output_(Config(mode), &clock_) {}
  StatusOutput& output() override { return output_; }
  Result<bool> ReadBack(std::size_t i) override { return output_.Level(i); }
  bool has_button() override { return true; }
  Status SetButton(bool pressed) override {
    pressed ? output_.PressButton() : output_.ReleaseButton();
    return Status::Ok();
  }
  int button_fd() override { return output_.button_event_fd(); }
  Result<ButtonEvent> ReadButtonEvent() override { return output_.ReadButtonEvent(); }

 private:
  static SimulatedStatusOutputConfig Config(StatusLineMode mode) {
    SimulatedStatusOutputConfig c;
    c.mode = mode;
    c.history_capacity = 64;
    c.has_button = true;
    return c;
  }
  ManualClock clock_;
  SimulatedStatusOutput output_;
};

std::unique_ptr<OutputUnderTest> MakeSim(StatusLineMode mode, std::string*) {
  return std::make_unique<SimOutput>(mode);
}

// --- libgpiod on a real (or gpio-sim) chip ---
#if SKYLOC_WITH_GPIOD
class GpioOutput final : public OutputUnderTest {
 public:
  explicit GpioOutput(const GpioStatusOutputConfig& c) : config_(c), output_(c) {}
  StatusOutput& output() override { return output_; }

  Result<bool> ReadBack(std::size_t i) override {
    SKYLOC_TRY(FindPins());
    return pins_->Level(config_.lines[i]);
  }
  bool has_button() override { return config_.button_line >= 0; }
  Status SetButton(bool pressed) override {
    SKYLOC_TRY(FindPins());
    return pins_->Pull(static_cast<unsigned>(config_.button_line), pressed);
  }
  int button_fd() override { return output_.button_event_fd(); }
  Result<ButtonEvent> ReadButtonEvent() override { return output_.ReadButtonEvent(); }

 private:
  // Found once, while the chip is open (its name locates the sysfs folder), and kept so
  // the lines can be read after Close() too.
  Status FindPins() {
    if (pins_.has_value())
      return Status::Ok();
    Result<testing::GpioSimPins> found = testing::GpioSimPins::Find(output_.chip_name());
    if (!found.ok())
      return found.status();
    pins_ = std::move(found).value();
    return Status::Ok();
  }

  GpioStatusOutputConfig config_;
  GpioStatusOutput output_;
  std::optional<testing::GpioSimPins> pins_;
};
#endif

std::unique_ptr<OutputUnderTest> MakeGpio(StatusLineMode mode, std::string* skip) {
#if SKYLOC_WITH_GPIOD
  const char* chip = testing::Env("SKYLOC_TEST_GPIOCHIP");
  if (chip == nullptr) {
    *skip =
        "no GPIO chip: set SKYLOC_TEST_GPIOCHIP=gpiochipN and SKYLOC_TEST_GPIO_LINES=a,b,c "
        "(the HIL VM does, with gpio-sim)";
    return nullptr;
  }
  GpioStatusOutputConfig c;
  std::snprintf(c.chip, sizeof(c.chip), "%s", chip);
  c.mode = mode;
  if (const char* lines = testing::Env("SKYLOC_TEST_GPIO_LINES")) {
    unsigned a = 0, b = 0, d = 0;
    const int n = std::sscanf(lines, "%u,%u,%u", &a, &b, &d);
    if (n < 1 || (mode == StatusLineMode::kLinePerState && n < 3)) {
      *skip =
          std::string("SKYLOC_TEST_GPIO_LINES='") + lines + "' needs three comma-separated offsets";
      return nullptr;
    }
    c.lines = {a, b, d};
  }
  if (const char* button = testing::Env("SKYLOC_TEST_GPIO_INPUT_LINE"))
    c.button_line = std::atoi(button);
  return std::make_unique<GpioOutput>(c);
#else
  (void)mode;
  *skip = "this build has no libgpiod driver (libgpiod-dev not installed for the target)";
  return nullptr;
#endif
}

struct OutputCase {
  const char* name;
  std::unique_ptr<OutputUnderTest> (*make)(StatusLineMode mode, std::string* skip);
  StatusLineMode mode;
};

const OutputCase kOutputCases[] = {
    {"SimulatedPerState", MakeSim, StatusLineMode::kLinePerState},
    {"SimulatedBlink", MakeSim, StatusLineMode::kBlink},
    {"GpiodPerState", MakeGpio, StatusLineMode::kLinePerState},
    {"GpiodBlink", MakeGpio, StatusLineMode::kBlink},
};

class StatusOutputSuite : public ::testing::TestWithParam<OutputCase> {
 protected:
  void SetUp() override {
    std::string skip;
    under_ = GetParam().make(GetParam().mode, &skip);
    if (!under_)
      GTEST_SKIP() << skip;
  }
  StatusOutput& output() { return under_->output(); }
  std::size_t lines() const { return GetParam().mode == StatusLineMode::kBlink ? 1 : 3; }

  // The read-back levels as a string, line 0 first: "100".
  std::string ReadAll() {
    std::string s;
    for (std::size_t i = 0; i < lines(); ++i) {
      Result<bool> level = under_->ReadBack(i);
      if (!level.ok()) {
        ADD_FAILURE() << level.status().message();
        return "?";
      }
      s += *level ? '1' : '0';
    }
    return s;
  }
  std::string Off() const { return std::string(lines(), '0'); }

  std::unique_ptr<OutputUnderTest> under_;
};

TEST_P(StatusOutputSuite, OpenDrivesEveryLineToTheSafeState) {
  ASSERT_OK(output().Open());
  EXPECT_EQ(ReadAll(), Off());
}

TEST_P(StatusOutputSuite, ShowsEachStateAsDocumented) {
  ASSERT_OK(output().Open());
  if (GetParam().mode == StatusLineMode::kLinePerState) {
    ASSERT_OK(output().Show(LocalisationState::kLost, 0.0f, milliseconds(0)));
    EXPECT_EQ(ReadAll(), "100");
    ASSERT_OK(output().Show(LocalisationState::kSearching, 0.3f, milliseconds(10)));
    EXPECT_EQ(ReadAll(), "010");
    ASSERT_OK(output().Show(LocalisationState::kLocalised, 0.9f, milliseconds(20)));
    EXPECT_EQ(ReadAll(), "001");
    return;
  }
  // Blink mode, expectations worked out from docs/DRIVERS.md:
  //   LOST 100 ms on / 2 s; SEARCHING 500 ms on / 1 s; LOCALISED (2 + 8c) Hz, 50 % duty.
  struct Step {
    LocalisationState state;
    float confidence;
    int at_ms;
    const char* expect;
  };
  const Step steps[] = {
      {LocalisationState::kLost, 0.0f, 4050, "1"},       // 50 ms into a 2 s period
      {LocalisationState::kLost, 0.0f, 4150, "0"},       // past the 100 ms flash
      {LocalisationState::kSearching, 0.0f, 7400, "1"},  // 400 ms into 1 s
      {LocalisationState::kSearching, 0.0f, 7600, "0"},
      {LocalisationState::kLocalised, 0.0f, 1200, "1"},  // 2 Hz: 200 ms into 500 ms
      {LocalisationState::kLocalised, 0.0f, 1300, "0"},
      {LocalisationState::kLocalised, 1.0f, 1040, "1"},  // 10 Hz: 40 ms into 100 ms
      {LocalisationState::kLocalised, 1.0f, 1060, "0"},
      {LocalisationState::kLocalised, 0.5f, 1020, "1"},  // 6 Hz: 1020 ms mod 166.667 ms = 20
      {LocalisationState::kLocalised, 0.5f, 1100, "0"},  // = 100 ms > 83.3 ms on-time
  };
  for (const Step& s : steps) {
    ASSERT_OK(output().Show(s.state, s.confidence, milliseconds(s.at_ms)));
    EXPECT_EQ(ReadAll(), s.expect)
        << LocalisationStateName(s.state) << " c=" << s.confidence << " t=" << s.at_ms << " ms";
  }
}

TEST_P(StatusOutputSuite, SafeStateTurnsEverythingOffAnyTime) {
  EXPECT_TRUE(output().SafeState().ok());  // before Open: harmless
  ASSERT_OK(output().Open());
  ASSERT_OK(
      output().Show(LocalisationState::kLost, 0.0f, milliseconds(2000)));  // lit in both modes
  EXPECT_NE(ReadAll(), Off());
  ASSERT_OK(output().SafeState());
  EXPECT_EQ(ReadAll(), Off());
  ASSERT_OK(output().SafeState());  // repeatable
  EXPECT_EQ(ReadAll(), Off());
  // Showing again after a safe state works (the pipeline recovers from a fault).
  ASSERT_OK(output().Show(LocalisationState::kLost, 0.0f, milliseconds(4000)));
  EXPECT_NE(ReadAll(), Off());
}

TEST_P(StatusOutputSuite, ShowBeforeOpenIsAnError) {
  EXPECT_EQ(output().Show(LocalisationState::kLocalised, 1.0f, milliseconds(0)).code(),
            StatusCode::kFailedPrecondition);
}

TEST_P(StatusOutputSuite, CloseLeavesTheLinesOffAndReopens) {
  ASSERT_OK(output().Open());
  ASSERT_OK(output().Show(LocalisationState::kLost, 0.0f, milliseconds(0)));
  EXPECT_NE(ReadAll(), Off());
  output().Close();
  // Released lines are not driven any more: on gpio-sim they fall to the pull-down.
  EXPECT_EQ(ReadAll(), Off());
  ASSERT_OK(output().Open());  // lines were released: requesting them again works
  EXPECT_EQ(ReadAll(), Off());
  output().Close();
  output().Close();  // harmless
}

// Between frames: the state shown last moves on with time alone (Refresh at the edges
// NextChange names), and nothing moves once the lines are safe.
TEST_P(StatusOutputSuite, RefreshMovesTheBlinkAtTheEdgesNextChangeNames) {
  ASSERT_OK(output().Open());
  EXPECT_EQ(output().NextChange(milliseconds(0)), StatusOutput::kNever);  // nothing shown
  ASSERT_OK(output().Show(LocalisationState::kLost, 0.0f, milliseconds(4050)));
  if (GetParam().mode == StatusLineMode::kLinePerState) {
    EXPECT_EQ(output().NextChange(milliseconds(4050)), StatusOutput::kNever);
    ASSERT_OK(output().Refresh(milliseconds(9999)));
    EXPECT_EQ(ReadAll(), "100");
  } else {
    // LOST: on 4000-4100 ms, off until 6000 ms.
    EXPECT_EQ(ReadAll(), "1");
    EXPECT_EQ(output().NextChange(milliseconds(4050)), milliseconds(4100));
    ASSERT_OK(output().Refresh(milliseconds(4099)));
    EXPECT_EQ(ReadAll(), "1");
    ASSERT_OK(output().Refresh(milliseconds(4100)));
    EXPECT_EQ(ReadAll(), "0");
    EXPECT_EQ(output().NextChange(milliseconds(4100)), milliseconds(6000));
    ASSERT_OK(output().Refresh(milliseconds(6000)));
    EXPECT_EQ(ReadAll(), "1");
  }
  ASSERT_OK(output().SafeState());
  EXPECT_EQ(output().NextChange(milliseconds(6000)), StatusOutput::kNever);
  ASSERT_OK(output().Refresh(milliseconds(8000)));  // LOST would be lit: the lines stay safe
  EXPECT_EQ(ReadAll(), Off());
}

// The call order is checked once, in StatusOutput, for every implementation.
TEST_P(StatusOutputSuite, CallsOutOfOrderAreRefusedTheSameWay) {
  EXPECT_FALSE(output().is_open());
  EXPECT_FALSE(output().has_button());
  EXPECT_EQ(output().ReadButtonEvent().status().code(), StatusCode::kFailedPrecondition);
  EXPECT_TRUE(output().Refresh(milliseconds(0)).ok());  // nothing shown: nothing to do
  EXPECT_EQ(output().NextChange(milliseconds(0)), StatusOutput::kNever);
  ASSERT_OK(output().Open());
  EXPECT_TRUE(output().is_open());
  EXPECT_EQ(output().Open().code(), StatusCode::kFailedPrecondition);
  EXPECT_TRUE(output().is_open());  // the refused Open() left it as it was
  ASSERT_OK(output().Show(LocalisationState::kSearching, 0.0f, milliseconds(100)));
  EXPECT_TRUE(output().is_showing());
  output().Close();
  EXPECT_FALSE(output().is_showing());
  EXPECT_EQ(output().Show(LocalisationState::kSearching, 0.0f, milliseconds(100)).code(),
            StatusCode::kFailedPrecondition);
}

TEST_P(StatusOutputSuite, ShowAndSafeStateDoNotAllocate) {
  ASSERT_TRUE(AllocationCounterActive());
  ASSERT_OK(output().Open());
  AllocationScope scope;
  for (int t = 0; t < 3000; t += 10) {
    const auto state = static_cast<LocalisationState>((t / 1000) % 3);
    const Status s = output().Show(state, 0.7f, milliseconds(t));
    // Between frames: the next edge and the lines moved to it.
    const Nanoseconds edge = output().NextChange(milliseconds(t));
    const Status r = output().Refresh(edge < milliseconds(t + 10) ? edge : milliseconds(t + 5));
    if (!s.ok() || !r.ok()) {
      ADD_FAILURE() << s.message() << r.message();
      break;
    }
  }
  // The fatal-error path: the safe state must be reachable without the heap.
  EXPECT_TRUE(output().SafeState().ok());
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST_P(StatusOutputSuite, ButtonEdgesArriveThroughTheEventFd) {
  if (!under_->has_button())
    GTEST_SKIP() << "no button line configured (SKYLOC_TEST_GPIO_INPUT_LINE)";
  ASSERT_OK(output().Open());
  EXPECT_EQ(under_->ReadButtonEvent().status().code(), StatusCode::kDeadlineExceeded);
  for (bool pressed : {true, false}) {
    ASSERT_OK(under_->SetButton(pressed));
    pollfd pfd{under_->button_fd(), POLLIN, 0};
    ASSERT_EQ(::poll(&pfd, 1, 2000), 1) << "no edge within 2 s";
    Result<ButtonEvent> event = under_->ReadButtonEvent();
    ASSERT_TRUE(event.ok()) << event.status().message();
    EXPECT_EQ(event->pressed, pressed);
  }
  EXPECT_EQ(under_->ReadButtonEvent().status().code(), StatusCode::kDeadlineExceeded);
}

// Shown by --gtest_list_tests (and so in CTest's test names) instead of raw bytes.
void PrintTo(const OutputCase& c, std::ostream* os) {
  *os << c.name;
}

std::string CaseName(const ::testing::TestParamInfo<OutputCase>& info) {
  return info.param.name;
}

INSTANTIATE_TEST_SUITE_P(AllOutputs, StatusOutputSuite, ::testing::ValuesIn(kOutputCases),
                         CaseName);

}  // namespace
}  // namespace skyloc::drivers
