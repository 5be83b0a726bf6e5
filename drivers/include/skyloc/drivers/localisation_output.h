// Where each frame's localisation goes for a robot's controller: the JSON line on stdout,
// a local socket any number of readers connect to, DDS topics a ROS 2 stack subscribes to
// (docs/OUTPUTS.md). The firmware builds one LocalisationMessage per frame (its fields
// and its JSON line, once) and hands it to every configured output from its publisher
// thread, never from the frame loop. An output never blocks on a reader: what it cannot
// deliver now is dropped and counted.
//
//   Closed --Open()--> Open --Publish()...--> Open --Close()--> Closed
//
// Open() may allocate; Publish() allocates nothing (the DDS output excepted: Cyclone DDS
// serialises each sample into memory of its own, on the publisher thread).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>

#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// The JSON line's schema version ("schema" in every line; docs/OUTPUTS.md). Bumped when a
// field changes meaning or goes; a new field does not bump it.
inline constexpr int kLocalisationSchema = 1;
// The most JSON text a message carries: the frame's line and, about once a second, the
// devices' record line after it, newlines included.
inline constexpr std::size_t kMaxJsonLine = 1024;

// One frame's result, as every output carries it. Trivially copyable: it goes through a
// lock-free queue by value.
struct LocalisationMessage {
  std::uint64_t frame = 0;        // the camera's sequence number
  std::int64_t timestamp_ns = 0;  // the frame's capture time on the camera's clock
  std::uint8_t state = 0;         // 0 LOST, 1 SEARCHING, 2 LOCALISED
  bool localising = false;        // repeat: the fields below mean something
  float confidence = 0;
  float uniqueness = 1;
  std::int64_t route_index = -1;   // the matched taught frame; -1: no match
  std::uint64_t route_length = 0;  // taught frames in the route
  double distance_along_m = 0;     // along the route to route_index; NaN: unknown
  float heading_deg = 0;           // NaN: no heading
  float heading_confidence = 0;    // NaN: no heading
  std::uint32_t latency_us = 0;    // capture to state shown
  std::uint32_t json_length = 0;   // bytes of the frame's line in `json`, newline included
  // Bytes of the devices' record line that follows it in `json` (firmware/device_report.h;
  // 0: none with this frame). The JSON outputs write it as a line (a message) of its own.
  std::uint32_t devices_length = 0;
  char json[kMaxJsonLine] = {};  // the frame's JSON line, then the devices' (no NUL)
};

// What an output could not deliver, and to whom it did (read after Close(), or from the
// publisher thread).
struct OutputCounters {
  std::uint64_t published = 0;        // messages given to Publish()
  std::uint64_t dropped = 0;          // deliveries not made: a reader's buffer full, a failed write
  std::uint64_t readers_seen = 0;     // socket: readers accepted over the run
  std::uint64_t readers_gone = 0;     // socket: readers that went away
  std::uint64_t readers_refused = 0;  // socket: readers turned away (max_readers reached)
};

class LocalisationOutput {
 public:
  virtual ~LocalisationOutput() = default;
  LocalisationOutput(const LocalisationOutput&) = delete;
  LocalisationOutput& operator=(const LocalisationOutput&) = delete;

  // Names the output in messages: "stdout", "socket /run/skyloc/localisation.sock".
  virtual const char* name() const = 0;
  // Opens the device, socket or participant. An error names it and the fix.
  virtual Status Open() = 0;
  // Publisher thread. Never blocks on a reader; counts what it cannot deliver.
  virtual void Publish(const LocalisationMessage& message) = 0;
  // Once a second from the publisher thread: the run's health, for outputs that carry it
  // (DDS's /diagnostics). `text` is "key=value" lines; the default ignores it.
  virtual void PublishHealth(const char* /*text*/) {}
  virtual void Close() = 0;
  virtual OutputCounters counters() const = 0;

 protected:
  LocalisationOutput() = default;
};

// The JSON lines on a stdio stream (stdout; tests give a memory stream): the frame's, then
// the devices' when the message has it. A failed write is counted as dropped.
class FileLinesOutput final : public LocalisationOutput {
 public:
  explicit FileLinesOutput(std::FILE* out) : out_(out) {}
  const char* name() const override { return "stdout"; }
  Status Open() override { return Status::Ok(); }
  void Publish(const LocalisationMessage& message) override;
  void Close() override {}
  OutputCounters counters() const override { return counters_; }

 private:
  std::FILE* out_;
  OutputCounters counters_;
};

// The in-memory twin: keeps the first `capacity` messages it is given (allocated at
// Open()), for tests of what the publisher hands over.
class MemoryOutput final : public LocalisationOutput {
 public:
  explicit MemoryOutput(std::size_t capacity) : capacity_(capacity) {}
  const char* name() const override { return "memory"; }
  Status Open() override;
  void Publish(const LocalisationMessage& message) override;
  void Close() override {}
  OutputCounters counters() const override { return counters_; }
  std::size_t size() const { return size_; }
  const LocalisationMessage& operator[](std::size_t i) const { return messages_[i]; }

 private:
  std::size_t capacity_;
  std::unique_ptr<LocalisationMessage[]> messages_;
  std::size_t size_ = 0;
  OutputCounters counters_;
};

struct UnixSocketOutputConfig {
  char path[108] = "/run/skyloc/localisation.sock";  // sockaddr_un's sun_path
  int max_readers = 8;   // readers connected at once; more are accepted and closed at once
  unsigned mode = 0660;  // the socket file's permissions (connecting needs write)
};

// A SOCK_SEQPACKET listening socket: each reader connect()s and then receives one JSON
// line per frame as one message (and the devices' record line as a message of its own) (record
// boundaries kept, in order, reliable on a local machine). Sends are non-blocking: a reader whose
// receive buffer is full misses that frame (counted as dropped), one that hung up is closed. New
// readers are accepted at the next Publish(). A socket file left by a crashed run is replaced;
// anything else at the path is an error.
class UnixSocketOutput final : public LocalisationOutput {
 public:
  explicit UnixSocketOutput(const UnixSocketOutputConfig& config);
  ~UnixSocketOutput() override;
  const char* name() const override { return name_; }
  Status Open() override;
  void Publish(const LocalisationMessage& message) override;
  void Close() override;
  OutputCounters counters() const override { return counters_; }
  int readers() const;  // connected now

 private:
  static constexpr int kMaxReaders = 64;
  void AcceptReaders();

  UnixSocketOutputConfig config_;
  char name_[128];
  int listen_fd_ = -1;
  int readers_[kMaxReaders];
  OutputCounters counters_;
};

}  // namespace skyloc::drivers
