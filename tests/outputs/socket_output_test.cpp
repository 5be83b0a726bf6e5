// The local socket output ([output] kinds = "socket") under the real frame loop on the
// built-in street: two readers at once receive every frame as the very line stdout gets;
// a reader that stops reading misses frames (counted) and the loop goes on; a reader that
// hangs up is closed; the frame path allocates nothing with the socket on.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "firmware/frame_loop.h"
#include "firmware/output_publisher.h"
#include "firmware/small_config.h"
#include "firmware/small_street_route.h"
#include "skyloc/drivers/localisation_output.h"
#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/street_source.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

const MonotonicClock kMonotonic;

// The socket output's configuration with its socket at `path`.
drivers::UnixSocketOutputConfig SocketAt(const std::string& path) {
  drivers::UnixSocketOutputConfig c;
  std::snprintf(c.path, sizeof c.path, "%s", path.c_str());
  return c;
}

int Connect(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
  if (fd >= 0 && ::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Reads messages until the server closes; counts them as they come.
class Reader {
 public:
  // keep_text: the messages are kept (text()); otherwise only counted, allocating nothing.
  explicit Reader(int fd, bool keep_text = true)
      : fd_(fd), keep_text_(keep_text), thread_([this] { Run(); }) {}
  ~Reader() {
    if (thread_.joinable())
      thread_.join();
    ::close(fd_);
  }
  void Join() { thread_.join(); }
  std::uint64_t received() const { return received_.load(); }
  const std::string& text() const { return text_; }  // after Join()

 private:
  void Run() {
    char message[drivers::kMaxJsonLine + 1];
    for (;;) {
      const ssize_t n = ::recv(fd_, message, sizeof message, 0);
      if (n <= 0)
        return;
      if (keep_text_)
        text_.append(message, static_cast<std::size_t>(n));
      received_.fetch_add(1);
    }
  }
  int fd_;
  bool keep_text_;
  std::string text_;
  std::atomic<std::uint64_t> received_{0};
  std::thread thread_;
};

// The test's pace: after each frame, waits until every listed reader has received it,
// so the readers' threads are never the reason a frame is missed (no timing in the test).
class WaitForReaders final : public FrameSink {
 public:
  explicit WaitForReaders(std::vector<const Reader*> readers) : readers_(std::move(readers)) {}
  void OnFrame(LoopMode, const FrameResult&, std::uint64_t) override {
    ++frames_;
    for (const Reader* r : readers_)
      while (r->received() < frames_)
        std::this_thread::yield();
  }

 private:
  std::vector<const Reader*> readers_;
  std::uint64_t frames_ = 0;
};

struct StreetRun {
  Pipeline pipeline{kMonotonic};
  RouteFrames route;
  std::unique_ptr<sim::FilmedStreet> filmed;
  drivers::SimulatedStatusOutput status{{}, &kMonotonic};

  void SetUp(std::uint64_t repeat_frames) {
    ClearSignalFlags();
    ASSERT_TRUE(pipeline.Init(testing::SmallConfig()).ok());
    testing::TeachSmallStreet(pipeline, 1, 300, &route);
    ASSERT_TRUE(pipeline.SetRoute(route).ok());
    filmed = std::make_unique<sim::FilmedStreet>(testing::SmallStreet(2, repeat_frames));
    ASSERT_TRUE(filmed->camera.Open().ok());
    ASSERT_TRUE(filmed->camera.Start().ok());
    ASSERT_TRUE(status.Open().ok());
  }

  // Repeats the street to its end with `outputs` fed by a publisher that waits for room,
  // `pace` beside it; the publisher has drained when this returns.
  void Repeat(std::span<drivers::LocalisationOutput* const> outputs, FrameSink* pace,
              LoopSummary* summary) {
    OutputPublisher publisher;
    ASSERT_TRUE(
        publisher.Start(outputs, &route, route.capacity(), PublishMode::kWaitWhenFull).ok());
    TeeSink sink(&publisher, pace);
    ASSERT_TRUE(
        RunFrameLoop(filmed->camera, &status, pipeline, nullptr, &sink, LoopOptions{}, summary)
            .ok());
    publisher.Stop();
  }
};

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

TEST(SocketOutput, TwoReadersGetEveryFrameAsTheStdoutLine) {
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  StreetRun street;
  street.SetUp(250);
  const std::string path = dir.path() + "/localisation.sock";
  const std::string stdout_path = dir.path() + "/stdout.jsonl";
  std::FILE* out = std::fopen(stdout_path.c_str(), "w");
  ASSERT_NE(out, nullptr);
  drivers::FileLinesOutput lines(out);
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0660u);

  Reader a(Connect(path)), b(Connect(path));
  drivers::LocalisationOutput* outputs[] = {&lines, &socket};
  WaitForReaders pace({&a, &b});
  LoopSummary summary;
  street.Repeat(outputs, &pace, &summary);
  socket.Close();  // the readers see the end
  std::fclose(out);
  a.Join();
  b.Join();
  EXPECT_EQ(summary.frames, 250u);
  const std::string stdout_text = Slurp(stdout_path);
  EXPECT_EQ(std::count(stdout_text.begin(), stdout_text.end(), '\n'), 250);
  EXPECT_EQ(a.text(), stdout_text);
  EXPECT_EQ(b.text(), stdout_text);
  // A real run: it localised, with distances along the taught street.
  EXPECT_NE(stdout_text.find("\"state\":\"LOCALISED\""), std::string::npos);
  EXPECT_NE(stdout_text.find("\"distance_m\":1"), std::string::npos);
  EXPECT_EQ(socket.counters().readers_seen, 2u);
  EXPECT_EQ(socket.counters().dropped, 0u);
  EXPECT_EQ(::access(path.c_str(), F_OK), -1) << "Close() leaves the socket file behind";
}

TEST(SocketOutput, AReaderThatStopsReadingMissesFramesAndBlocksNothing) {
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  StreetRun street;
  street.SetUp(400);
  const std::string path = dir.path() + "/localisation.sock";
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  const int dead = Connect(path);  // connects, never reads
  ASSERT_GE(dead, 0);
  Reader live(Connect(path));
  drivers::LocalisationOutput* outputs[] = {&socket};
  WaitForReaders pace({&live});
  LoopSummary summary;
  street.Repeat(outputs, &pace, &summary);
  // The dead reader's queue holds what fits; everything after it was dropped for it
  // alone: the live reader got all 400.
  char message[drivers::kMaxJsonLine];
  std::uint64_t queued = 0;
  while (::recv(dead, message, sizeof message, MSG_DONTWAIT) > 0)
    ++queued;
  socket.Close();
  live.Join();
  ::close(dead);
  EXPECT_EQ(summary.frames, 400u);
  EXPECT_EQ(live.received(), 400u);
  EXPECT_GT(queued, 0u);
  EXPECT_LT(queued, 400u);
  EXPECT_EQ(socket.counters().dropped, 400u - queued);
}

TEST(SocketOutput, HungUpReadersAreClosedAndExtraReadersRefused) {
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  const std::string path = dir.path() + "/localisation.sock";
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  c.max_readers = 1;
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  const int first = Connect(path), second = Connect(path);
  ASSERT_GE(first, 0);
  ASSERT_GE(second, 0);
  drivers::LocalisationMessage m;
  m.json_length = 3;
  std::memcpy(m.json, "{}\n", 3);
  socket.Publish(m);  // accepts the first, turns the second away
  EXPECT_EQ(socket.readers(), 1);
  EXPECT_EQ(socket.counters().readers_refused, 1u);
  char got[16];
  EXPECT_EQ(::recv(first, got, sizeof got, 0), 3);
  EXPECT_EQ(::recv(second, got, sizeof got, 0), 0) << "the refused reader sees the end";
  ::close(first);
  ::close(second);
  socket.Publish(m);
  EXPECT_EQ(socket.readers(), 0);
  EXPECT_EQ(socket.counters().readers_gone, 1u);
  socket.Close();
}

// The devices' record that rides in a frame's message (about once a second) reaches a
// reader as a message of its own after the frame's line, as stdout gets it as a line of
// its own.
TEST(SocketOutput, TheDevicesRecordIsAMessageOfItsOwn) {
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  const std::string path = dir.path() + "/localisation.sock";
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  const int reader = Connect(path);
  ASSERT_GE(reader, 0);
  drivers::LocalisationMessage m;
  const std::string frame = "{\"schema\":1,\"frame\":7}\n", devices = "{\"devices\":{}}\n";
  std::memcpy(m.json, frame.data(), frame.size());
  std::memcpy(m.json + frame.size(), devices.data(), devices.size());
  m.json_length = static_cast<std::uint32_t>(frame.size());
  m.devices_length = static_cast<std::uint32_t>(devices.size());
  socket.Publish(m);
  m.devices_length = 0;
  socket.Publish(m);
  socket.Close();
  std::vector<std::string> got;
  char message[64];
  for (ssize_t n; (n = ::recv(reader, message, sizeof message, 0)) > 0;)
    got.emplace_back(message, static_cast<std::size_t>(n));
  ::close(reader);
  EXPECT_EQ(got, (std::vector<std::string>{frame, devices, frame}));

  char* text = nullptr;
  std::size_t size = 0;
  std::FILE* f = open_memstream(&text, &size);
  ASSERT_NE(f, nullptr);
  drivers::FileLinesOutput lines(f);
  m.devices_length = static_cast<std::uint32_t>(devices.size());
  lines.Publish(m);
  std::fclose(f);
  EXPECT_EQ(std::string(text, size), frame + devices);
  std::free(text);
}

TEST(SocketOutput, ReplacesAStaleSocketButNeverAFile) {
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  const std::string path = dir.path() + "/localisation.sock";
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  {
    // A socket file left behind, as by a crash: no Close().
    const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
    ::close(fd);
  }
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  socket.Close();
  { std::ofstream(path) << "not a socket"; }
  drivers::UnixSocketOutput refused(c);
  const Status s = refused.Open();
  EXPECT_EQ(s.code(), StatusCode::kAlreadyExists);
  EXPECT_NE(std::string(s.message()).find(path), std::string::npos) << s.message();
  EXPECT_NE(std::string(s.message()).find("socket_path"), std::string::npos) << s.message();
  EXPECT_EQ(Slurp(path), "not a socket");
  std::snprintf(c.path, sizeof c.path, "%s/no/such/folder.sock", dir.path().c_str());
  drivers::UnixSocketOutput nowhere(c);
  EXPECT_EQ(nowhere.Open().code(), StatusCode::kNotFound);
}

// The frame path with the socket on (a reader reading, one not) allocates nothing, on any
// thread: the publisher's and the socket's included.
TEST(SocketOutput, FramePathAllocatesNothingWithTheSocketOn) {
  ASSERT_TRUE(AllocationCounterActive());
  skyloc::testing::ScratchDir dir("skyloc-socket-");
  StreetRun street;
  street.SetUp(0);
  const std::string path = dir.path() + "/localisation.sock";
  drivers::UnixSocketOutputConfig c = SocketAt(path);
  drivers::UnixSocketOutput socket(c);
  ASSERT_TRUE(socket.Open().ok());
  const int dead = Connect(path);
  Reader live(Connect(path), false);
  drivers::LocalisationOutput* outputs[] = {&socket};
  OutputPublisher publisher;
  ASSERT_TRUE(
      publisher.Start(outputs, &street.route, street.route.capacity(), PublishMode::kWaitWhenFull)
          .ok());
  LoopOptions options;
  options.max_frames = 10;
  LoopSummary summary;
  ASSERT_TRUE(RunFrameLoop(street.filmed->camera, &street.status, street.pipeline, nullptr,
                           &publisher, options, &summary)
                  .ok());
  options.max_frames = 2000;
  AllocationScope scope;
  const Status s = RunFrameLoop(street.filmed->camera, &street.status, street.pipeline, nullptr,
                                &publisher, options, &summary);
  publisher.Stop();
  const std::uint64_t allocations = scope.allocations();
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(socket.counters().dropped, 0u);  // the dead reader's
  socket.Close();
  live.Join();
  ::close(dead);
}

}  // namespace
}  // namespace skyloc::firmware
