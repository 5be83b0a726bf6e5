// The route database: round trip, rejection of every kind of damage with the chunk named,
// settings checks, and crash safety (a child killed with SIGKILL while teaching).
#include "firmware/route_db.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/crc32.h"
#include "support/emulator.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

constexpr std::uint32_t kDim = 5;

RouteDbSettings Settings() {
  RouteDbSettings s;
  s.descriptor_kind = 1;
  s.bands = kDim;
  s.rings = 3;
  s.longitudes = 16;
  s.dim = kDim;
  s.normalisation = 0;
  s.lens_hash = 0x1234567890abcdefull;
  s.lens.known = true;
  s.lens.model = 0;  // equidistant
  s.lens.width = 320;
  s.lens.height = 240;
  s.lens.centre_x = 159.5;
  s.lens.centre_y = 119.5;
  s.lens.radius_px = 120;
  s.lens.fov_deg = 185;
  s.lens.fx = 100.25;
  s.lens.fy = 100.5;
  s.lens.k = {0.01, -0.002, 0.0003, 0};
  s.lens.pitch_deg = 1.5;
  return s;
}

// Where the first chunk starts in a file this skyloc writes (header + lens record).
constexpr std::size_t kDataOffset = RouteDbDataOffset(kRouteDbVersion);

template <typename T>
T Load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <typename T>
void Store(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

// The file (complete chunks only) rewritten as an older version, by the layouts
// docs/ROUTE_DB.md gives, independently of the writer. Version 5 keeps the compact record
// (u64 timestamp, u8 flags, i8 exponent, six f32 pose values, dim 16-bit codes); below it
// every frame record becomes the 64-byte fixed part (u64 timestamp, u32 flags, u32
// reserved, six f64 pose values) and dim f32 values (16-bit code x 2^exponent). A file
// with strips (`columns` > 0) gives versions 4 and 5 a byte a column from `strips`
// (frames x columns, the bytes taught: version 6's 4 bits cannot give them back), and the
// strip record's bits field (version 6) goes back to its reserved 0. The header says
// `version`; below version 4 the strip record is cut out, below version 3 the lens record
// too (those versions have none); version 1 also loses the cap.
std::vector<std::uint8_t> AsVersion(const std::vector<std::uint8_t>& current, std::uint32_t version,
                                    std::size_t columns = 0,
                                    const std::vector<std::uint8_t>& strips = {}) {
  std::vector<std::uint8_t> b(current.begin(), current.begin() + static_cast<long>(kDataOffset));
  const std::size_t compact = 34 + 2 * kDim;
  const std::size_t new_record = compact + (columns > 0 ? 2 + (columns + 1) / 2 : 0);
  const std::size_t old_columns = version >= 4 ? columns : 0;
  const std::size_t old_record = (version >= 5 ? compact : 64 + 4 * kDim) + old_columns;
  Store<std::uint32_t>(b.data() + 48, static_cast<std::uint32_t>(old_record));
  std::size_t frame = 0;
  for (std::size_t o = kDataOffset; o + kRouteDbChunkHeaderBytes <= current.size();) {
    std::uint8_t header[kRouteDbChunkHeaderBytes];
    std::memcpy(header, current.data() + o, sizeof header);
    const std::uint32_t count = Load<std::uint32_t>(header + 16);
    std::vector<std::uint8_t> payload(count * old_record, 0);
    for (std::size_t i = 0; i < count; ++i, ++frame) {
      const std::uint8_t* in = current.data() + o + kRouteDbChunkHeaderBytes + i * new_record;
      std::uint8_t* out = payload.data() + i * old_record;
      if (version >= 5) {
        std::memcpy(out, in, compact);
      } else {
        std::memcpy(out, in, 8);  // timestamp
        Store<std::uint32_t>(out + 8, in[8]);
        for (std::size_t k = 0; k < 6; ++k)
          Store<double>(out + 16 + 8 * k, static_cast<double>(Load<float>(in + 10 + 4 * k)));
        const int exponent = static_cast<std::int8_t>(in[9]);
        for (std::size_t k = 0; k < kDim; ++k)
          Store<float>(
              out + 64 + 4 * k,
              std::ldexp(static_cast<float>(Load<std::uint16_t>(in + 34 + 2 * k)), exponent));
      }
      if (old_columns > 0)
        std::memcpy(out + old_record - old_columns, strips.data() + frame * columns, columns);
    }
    Store<std::uint32_t>(header + 20, static_cast<std::uint32_t>(payload.size()));
    Store<std::uint32_t>(header + 24, Crc32(payload));
    Store<std::uint32_t>(header + 28, Crc32({header, 28}));
    b.insert(b.end(), header, header + sizeof header);
    b.insert(b.end(), payload.begin(), payload.end());
    o += kRouteDbChunkHeaderBytes + count * new_record;
  }
  std::uint8_t* strip_record = b.data() + kRouteDbHeaderBytes + kRouteDbLensRecordBytes;
  Store<std::uint32_t>(strip_record + 16, 0);
  Store<std::uint32_t>(strip_record + 28, Crc32({strip_record, 28}));
  std::memcpy(b.data() + 8, &version, 4);
  if (version < 4) {
    b.erase(b.begin() + static_cast<long>(RouteDbDataOffset(version)),
            b.begin() + static_cast<long>(kDataOffset));
    const auto offset = static_cast<std::uint32_t>(RouteDbDataOffset(version));
    std::memcpy(b.data() + 12, &offset, 4);
  }
  if (version < 2)
    std::memset(b.data() + 52, 0, 8);
  const std::uint32_t crc = Crc32({b.data(), 60});
  std::memcpy(b.data() + 60, &crc, 4);
  return b;
}

// Frame i's content: every value depends on i, so a misplaced record is noticed. The
// descriptor is one a version-5 record holds exactly (integers below 2^16, here squares,
// times a power of two that changes from frame to frame), and the pose one a float does.
void FrameContent(std::size_t i, RouteFrameMeta* meta, float* descriptor) {
  meta->timestamp_ns = 1000000ull * i + 7;
  meta->pose.reset();
  if (i % 3 != 0) {
    const double base = static_cast<double>(i) * 0.5;
    meta->pose = drivers::Pose{base, base + 1, base + 2, base + 3, base + 4, base + 5};
  }
  const int exponent = -3 - static_cast<int>(i % 5);
  const auto square = [](std::size_t c) { return static_cast<float>(c * c); };
  descriptor[0] = std::ldexp(square(255 - i % 75), exponent);
  for (std::size_t k = 1; k < kDim; ++k)
    descriptor[k] = std::ldexp(square((i * 31 + 17 * k) % 181), exponent);
}

void ExpectFrames(const RouteFrames& frames, std::size_t n) {
  ASSERT_EQ(frames.size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    RouteFrameMeta want;
    float d[kDim];
    FrameContent(i, &want, d);
    ASSERT_EQ(frames.meta(i).timestamp_ns, want.timestamp_ns) << i;
    ASSERT_EQ(frames.meta(i).pose.has_value(), want.pose.has_value()) << i;
    if (want.pose) {
      const RouteFrameMeta loaded = frames.meta(i);
      const drivers::Pose& got = *loaded.pose;
      ASSERT_EQ(got.x_m, want.pose->x_m) << i;
      ASSERT_EQ(got.y_m, want.pose->y_m) << i;
      ASSERT_EQ(got.z_m, want.pose->z_m) << i;
      ASSERT_EQ(got.roll_deg, want.pose->roll_deg) << i;
      ASSERT_EQ(got.pitch_deg, want.pose->pitch_deg) << i;
      ASSERT_EQ(got.yaw_deg, want.pose->yaw_deg) << i;
    }
    for (std::size_t k = 0; k < kDim; ++k)
      ASSERT_EQ(frames.descriptor(i)[k], d[k]) << i << "," << k;
  }
}

class RouteDbTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = dir_ + "/route.db";
    ASSERT_TRUE(frames_.Allocate(10000, kDim).ok());
  }

  // Writes n frames, flushing every `flush_every`, and commits if asked.
  void Teach(std::size_t n, std::size_t flush_every, bool commit) {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), flush_every, true).ok());
    for (std::size_t i = 0; i < n; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      ASSERT_TRUE(w.Append(meta, d).ok());
    }
    if (commit) {
      ASSERT_TRUE(w.Commit().ok());
    } else {
      ASSERT_TRUE(w.Flush().ok());
    }
  }

  std::vector<std::uint8_t> Bytes() const {
    std::ifstream in(path_, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  Status Parse(const std::vector<std::uint8_t>& bytes,
               RouteDbLoadPolicy policy = RouteDbLoadPolicy::kStrict,
               RouteDbLoadReport* report = nullptr) {
    const RouteDbSettings want = Settings();
    return ParseRouteDb(bytes, &want, policy, &frames_, report);
  }

  skyloc::testing::ScratchDir scratch_{"skyloc_route_db_"};
  const std::string& dir_ = scratch_.path();
  std::string path_;
  RouteFrames frames_;
};

// Independent of the loader: where chunk k (1-based) starts in a route of n frames
// written with flush_every f (every frame chunk holds f frames but the last; the commit
// record is the chunk after them).
std::size_t ChunkOffset(std::size_t k, std::size_t f, std::size_t n) {
  std::size_t offset = kDataOffset;
  for (std::size_t j = 1; j < k; ++j) {
    const std::size_t frames = std::min(f, n - (j - 1) * f);
    offset += kRouteDbChunkHeaderBytes + frames * RouteDbRecordBytes(kRouteDbVersion, kDim, 0);
  }
  return offset;
}

TEST_F(RouteDbTest, RoundTrip) {
  Teach(137, 10, true);
  RouteDbLoadReport report;
  const RouteDbSettings want = Settings();
  Status s = LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &frames_, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(report.committed);
  EXPECT_EQ(report.frames, 137u);
  EXPECT_EQ(report.chunks, 14u);
  EXPECT_EQ(report.settings, Settings());  // the lens record too
  EXPECT_EQ(report.version, 6u);
  ExpectFrames(frames_, 137);
  EXPECT_FALSE(frames_.has_strips());
  // The size follows from the format alone.
  EXPECT_EQ(Bytes().size(), kRouteDbHeaderBytes + kRouteDbLensRecordBytes +
                                kRouteDbStripRecordBytes + 15 * kRouteDbChunkHeaderBytes +
                                137 * RouteDbRecordBytes(kRouteDbVersion, kDim, 0));
  // Version 5 and 6's record: u64 timestamp, u8 flags, i8 exponent, six f32, two bytes a
  // value.
  EXPECT_EQ(RouteDbRecordBytes(kRouteDbVersion, kDim, 0), 34 + 2 * kDim);
}

// Teach no longer leaves a route without frames (it removes the file), but a file that
// is one (an older skyloc wrote it) still loads: the header, then the commit record.
TEST_F(RouteDbTest, EmptyCommittedRouteLoads) {
  Teach(1, 10, true);
  std::vector<std::uint8_t> bytes = Bytes();
  bytes.resize(kDataOffset + kRouteDbChunkHeaderBytes);
  std::uint8_t* commit = bytes.data() + kDataOffset;
  std::memset(commit, 0, kRouteDbChunkHeaderBytes);
  const std::uint32_t marker = 0x4B4E4843u, type = 2, payload_crc = Crc32({});
  std::memcpy(commit, &marker, 4);
  std::memcpy(commit + 4, &type, 4);
  std::memcpy(commit + 24, &payload_crc, 4);
  const std::uint32_t header_crc = Crc32({commit, 28});
  std::memcpy(commit + 28, &header_crc, 4);
  EXPECT_TRUE(Parse(bytes).ok());
  EXPECT_EQ(frames_.size(), 0u);
}

TEST_F(RouteDbTest, RefusesToReplaceATaughtRoute) {
  Teach(3, 10, true);
  RouteDbWriter w;
  Status s = w.Create(path_.c_str(), Settings(), 10, false);
  EXPECT_EQ(s.code(), StatusCode::kAlreadyExists);
  EXPECT_NE(std::string(s.message()).find("already exists"), std::string::npos);
  EXPECT_TRUE(Parse(Bytes()).ok());
  EXPECT_EQ(frames_.size(), 3u);
}

// teach --force: the old route stays whole (loadable, every frame) until the new one is
// committed; a teach killed before that costs nothing. The frames go to FILE.tmp, which
// the commit renames over the old route.
TEST_F(RouteDbTest, ForceKeepsTheOldRouteUntilTheNewOneCommits) {
  Teach(25, 10, true);
  const std::vector<std::uint8_t> old_route = Bytes();
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 10, true).ok());
    EXPECT_TRUE(w.replacing());
    EXPECT_EQ(std::string(w.write_path()), path_ + ".tmp");
    for (std::size_t i = 0; i < 15; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      ASSERT_TRUE(w.Append(meta, d).ok());
    }
    EXPECT_EQ(Bytes(), old_route) << "the old route changed before the new one committed";
  }  // closed without a commit: a killed teach
  EXPECT_EQ(Bytes(), old_route);
  ASSERT_TRUE(Parse(Bytes()).ok());
  ExpectFrames(frames_, 25);

  RouteDbWriter w;
  ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 10, true).ok());
  for (std::size_t i = 0; i < 7; ++i) {
    RouteFrameMeta meta;
    float d[kDim];
    FrameContent(i, &meta, d);
    ASSERT_TRUE(w.Append(meta, d).ok());
  }
  ASSERT_TRUE(w.Commit().ok());
  ASSERT_TRUE(Parse(Bytes()).ok());
  ExpectFrames(frames_, 7);
  EXPECT_NE(::access((path_ + ".tmp").c_str(), F_OK), 0) << "FILE.tmp left behind";
}

// Appends frames first..first+n-1 (FrameContent) to an open writer.
void AppendFrames(RouteDbWriter* w, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    RouteFrameMeta meta;
    float d[kDim];
    FrameContent(i, &meta, d);
    ASSERT_TRUE(w->Append(meta, d).ok());
  }
}

// Two teaches on one route, one process (each writer opens the route's lock on its own
// file description, so the lock excludes within a process as between processes): while a
// `teach --force` writes FILE.tmp, a second one is refused before it touches FILE.tmp, and
// the first commits every frame it taught.
TEST_F(RouteDbTest, ASecondForceTeachIsRefusedBeforeItTouchesAnything) {
  Teach(25, 10, true);
  RouteDbWriter first;
  ASSERT_TRUE(first.Create(path_.c_str(), Settings(), 10, true).ok());
  AppendFrames(&first, 15);  // one chunk on the disk, five frames pending
  const std::string tmp = path_ + ".tmp";
  struct stat before {};
  ASSERT_EQ(::stat(tmp.c_str(), &before), 0);

  RouteDbWriter second;
  const Status s = second.Create(path_.c_str(), Settings(), 10, true);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();
  EXPECT_NE(std::string(s.message()).find("is being taught"), std::string::npos) << s.message();
  struct stat after {};
  ASSERT_EQ(::stat(tmp.c_str(), &after), 0);
  EXPECT_EQ(after.st_size, before.st_size) << "the refused teach changed FILE.tmp";

  ASSERT_TRUE(first.Commit().ok());
  const Status loaded = Parse(Bytes());
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  ExpectFrames(frames_, 15);
}

// A plain teach is writing a new route: a `teach --force` on the same path is refused and
// the plain teach's frames are what the file holds.
TEST_F(RouteDbTest, AForceTeachIsRefusedWhileAPlainTeachWrites) {
  RouteDbWriter plain;
  ASSERT_TRUE(plain.Create(path_.c_str(), Settings(), 10, false).ok());
  AppendFrames(&plain, 21);

  RouteDbWriter force;
  const Status s = force.Create(path_.c_str(), Settings(), 10, true);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();
  if (s.ok()) {
    AppendFrames(&force, 3);
    EXPECT_TRUE(force.Commit().ok());
  }
  ASSERT_TRUE(plain.Commit().ok());
  const Status loaded = Parse(Bytes());
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  ExpectFrames(frames_, 21);
}

// A `teach --force` that commits nothing (stopped before its first frame) keeps the old
// route, byte for byte, and leaves no FILE.tmp; a new route that gets no frame leaves no
// file at all (it would only block the next teach).
TEST_F(RouteDbTest, ATeachThatCommitsNothingLeavesThePathAsItWas) {
  Teach(25, 10, true);
  const std::vector<std::uint8_t> old_route = Bytes();
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 10, true).ok());
    const Status s = w.Commit();
    EXPECT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(w.discarded());
    EXPECT_FALSE(w.committed());
  }
  EXPECT_EQ(Bytes(), old_route);
  EXPECT_NE(::access((path_ + ".tmp").c_str(), F_OK), 0) << "FILE.tmp left behind";

  const std::string fresh = dir_ + "/fresh.db";
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(fresh.c_str(), Settings(), 10, false).ok());
    EXPECT_TRUE(w.Commit().ok());
  }
  EXPECT_NE(::access(fresh.c_str(), F_OK), 0) << "an empty route file was left behind";
}

// A full disk before the first chunk of a `teach --force` (RLIMIT_FSIZE in a child): no
// frame reached the disk, so the old route stays, whole.
TEST_F(RouteDbTest, DiskFullBeforeTheFirstChunkKeepsTheOldRoute) {
  if (skyloc::testing::UnderUserModeEmulator())
    GTEST_SKIP() << "qemu-user spins in a forked child past RLIMIT_FSIZE (support/emulator.h)";
  Teach(25, 10, true);
  const std::vector<std::uint8_t> old_route = Bytes();
  const std::size_t limit = kDataOffset + 100;  // the header fits, no chunk does
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{static_cast<rlim_t>(limit), static_cast<rlim_t>(limit)};
    if (::setrlimit(RLIMIT_FSIZE, &lim) != 0)
      ::_exit(2);
    RouteDbWriter w;
    if (!w.Create(path_.c_str(), Settings(), 10, true).ok())
      ::_exit(3);
    for (std::size_t i = 0; i < 10; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      (void)w.Append(meta, d);
    }
    const Status s = w.Commit();
    ::_exit(s.ok() ? 4 : 0);  // the frames did not fit: an error, whatever else happens
  }
  int wstatus = 0;
  ASSERT_EQ(::waitpid(child, &wstatus, 0), child);
  ASSERT_TRUE(WIFEXITED(wstatus)) << wstatus;
  EXPECT_EQ(WEXITSTATUS(wstatus), 0);
  EXPECT_EQ(Bytes(), old_route) << "the old route was replaced by one without frames";
  EXPECT_NE(::access((path_ + ".tmp").c_str(), F_OK), 0) << "FILE.tmp left behind";
}

// A FILE.tmp left by a killed `teach --force` is replaced by the next teach, which says
// what it held (replaced_tmp()); while a teach runs, RouteBeingTaught says so.
TEST_F(RouteDbTest, AStaleTmpIsReportedWhenReplaced) {
  Teach(25, 10, true);
  {
    RouteDbWriter killed;
    ASSERT_TRUE(killed.Create(path_.c_str(), Settings(), 10, true).ok());
    AppendFrames(&killed, 15);
    long pid = 0;
    EXPECT_TRUE(RouteBeingTaught(path_.c_str(), &pid));
    EXPECT_EQ(pid, static_cast<long>(::getpid()));
  }  // closed without a commit, as a killed teach's file is
  long pid = 0;
  EXPECT_FALSE(RouteBeingTaught(path_.c_str(), &pid));
  const RouteTmpReport stale = InspectRouteTmp(path_.c_str());
  EXPECT_TRUE(stale.exists);
  EXPECT_TRUE(stale.loads);
  EXPECT_EQ(stale.frames, 10u);

  RouteDbWriter next;
  ASSERT_TRUE(next.Create(path_.c_str(), Settings(), 10, true).ok());
  EXPECT_TRUE(next.replaced_tmp().exists);
  EXPECT_EQ(next.replaced_tmp().frames, 10u);
  AppendFrames(&next, 4);
  ASSERT_TRUE(next.Commit().ok());
  ASSERT_TRUE(Parse(Bytes()).ok());
  ExpectFrames(frames_, 4);
  EXPECT_FALSE(InspectRouteTmp(path_.c_str()).exists);
  EXPECT_NE(::access((path_ + ".lock").c_str(), F_OK), 0) << "the lock file was left behind";
}

// A symlink, FIFO (or device node) at the route path is refused even with --force; it is
// left as it was, never replaced by a regular file.
TEST_F(RouteDbTest, RefusesToReplaceASymlinkOrFifo) {
  const std::string target = dir_ + "/target.db";
  {
    std::ofstream out(target);
    out << "not ours";
  }
  ASSERT_EQ(::symlink(target.c_str(), path_.c_str()), 0);
  RouteDbWriter w;
  Status s = w.Create(path_.c_str(), Settings(), 10, true);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message()).find("is a symbolic link"), std::string::npos) << s.message();
  struct stat st {};
  ASSERT_EQ(::lstat(path_.c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode));
  std::ifstream in(target);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "not ours");

  const std::string fifo = dir_ + "/fifo.db";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  s = w.Create(fifo.c_str(), Settings(), 10, true);
  EXPECT_NE(std::string(s.message()).find("is a FIFO"), std::string::npos) << s.message();
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST_F(RouteDbTest, UncommittedFileNeedsRecovery) {
  Teach(25, 10, false);
  Status strict = Parse(Bytes());
  ASSERT_FALSE(strict.ok());
  EXPECT_NE(std::string(strict.message()).find("no commit record"), std::string::npos)
      << strict.message();
  EXPECT_NE(std::string(strict.message()).find("skyloc route recover"), std::string::npos);
  RouteDbLoadReport report;
  ASSERT_TRUE(Parse(Bytes(), RouteDbLoadPolicy::kRecoverInterrupted, &report).ok());
  EXPECT_FALSE(report.committed);
  ExpectFrames(frames_, 25);

  ASSERT_TRUE(RecoverRouteDb(path_.c_str(), &report).ok());
  Status after = Parse(Bytes());
  ASSERT_TRUE(after.ok()) << after.message();
  ExpectFrames(frames_, 25);
}

TEST_F(RouteDbTest, SettingsMismatchNamesTheSetting) {
  Teach(5, 10, true);
  RouteDbSettings other = Settings();
  other.bands = 7;
  Status s = ParseRouteDb(Bytes(), &other, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message())
                .find("taught with [descriptor] bands = 5 but this "
                      "configuration has 7: set [descriptor] bands = 5 or teach again"),
            std::string::npos)
      << s.message();
  // Another grid: says which key sets it, and what the default was before it changed.
  other = Settings();
  other.rings += 1;
  s = ParseRouteDb(Bytes(), &other, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message()).find("[descriptor] rings = "), std::string::npos)
      << s.message();
  EXPECT_NE(std::string(s.message())
                .find(": set [descriptor] grid as taught (\"auto\" was the default before "
                      "2026-11-26), or teach again"),
            std::string::npos)
      << s.message();
  // A version-3 file compares the lens parameters, not the hash.
  other = Settings();
  other.lens_hash = 1;
  s = ParseRouteDb(Bytes(), &other, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_TRUE(s.ok()) << s.message();
}

TEST_F(RouteDbTest, NormalisationMismatchNamesBothAndTheSetting) {
  Teach(5, 10, true);  // normalisation 0: "none", the default before unit_l2
  RouteDbSettings unit_l2 = Settings();
  unit_l2.normalisation = 2;
  const Status s = ParseRouteDb(Bytes(), &unit_l2, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message())
                .find("taught with [descriptor] normalisation = \"none\" but this configuration "
                      "has \"unit_l2\": set normalisation = \"none\""),
            std::string::npos)
      << s.message();
}

TEST_F(RouteDbTest, GravityCapMismatchIsNamed) {
  Teach(5, 10, true);
  RouteDbSettings capped = Settings();
  capped.gravity_cap_cdeg = 3000;
  capped.gravity_cap_taper_cdeg = 1000;
  Status s = ParseRouteDb(Bytes(), &capped, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message())
                .find("taught with no gravity cap, this configuration has a gravity cap above "
                      "30.00 deg"),
            std::string::npos)
      << s.message();
}

// Version 1 had no cap (bytes 52..59 reserved, 0): it still loads, as a route without one;
// a version newer than this skyloc's is refused naming both versions.
TEST_F(RouteDbTest, ReadsVersionOneAndRefusesANewerVersion) {
  Teach(5, 10, true);
  const std::vector<std::uint8_t> v1 = AsVersion(Bytes(), 1);
  RouteDbLoadReport report;
  const RouteDbSettings want = Settings();
  Status s = ParseRouteDb(v1, &want, RouteDbLoadPolicy::kStrict, &frames_, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.version, 1u);
  EXPECT_EQ(report.settings.gravity_cap_cdeg, kNoGravityCap);
  EXPECT_FALSE(report.settings.lens.known);
  ExpectFrames(frames_, 5);
  std::vector<std::uint8_t> v7 = Bytes();
  const std::uint32_t seven = 7;
  std::memcpy(v7.data() + 8, &seven, 4);
  s = Parse(v7);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("version 7; this skyloc reads versions 1 to 6"),
            std::string::npos)
      << s.message();
}

// A version-2 file has no lens record: it loads, the lens is unknown, and the check falls
// back to the hash, saying so in hex.
TEST_F(RouteDbTest, VersionTwoFallsBackToTheLensHash) {
  Teach(12, 5, true);
  const std::vector<std::uint8_t> v2 = AsVersion(Bytes(), 2);
  RouteDbLoadReport report;
  RouteDbSettings want = Settings();
  Status s = ParseRouteDb(v2, &want, RouteDbLoadPolicy::kStrict, &frames_, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.version, 2u);
  EXPECT_FALSE(report.settings.lens.known);
  EXPECT_EQ(report.settings.lens_hash, Settings().lens_hash);
  ExpectFrames(frames_, 12);
  char text[200];
  FormatRouteDbLens(report.settings.lens, text, sizeof text);
  EXPECT_NE(std::string(text).find("not stored"), std::string::npos) << text;

  want.lens_hash = 0xabcull;
  s = ParseRouteDb(v2, &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message())
                .find("lens hash 1234567890abcdef, this configuration has 0000000000000abc; the "
                      "file is older than version 3 and stores no lens parameters"),
            std::string::npos)
      << s.message();
  // Recovery keeps an old file's version (it only cuts and appends).
  ASSERT_EQ(std::remove(path_.c_str()), 0);
  Teach(7, 5, false);
  std::vector<std::uint8_t> v2_torn = AsVersion(Bytes(), 2);
  {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(v2_torn.data()), static_cast<long>(v2_torn.size()));
  }
  ASSERT_TRUE(RecoverRouteDb(path_.c_str(), &report).ok());
  want = Settings();
  s = ParseRouteDb(Bytes(), &want, RouteDbLoadPolicy::kStrict, &frames_, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.version, 2u);
  ExpectFrames(frames_, 7);
}

// Frame i's strip as taught, a byte a column: frame 0 flat, the others 23 i grey levels wide.
std::vector<std::uint8_t> TaughtStrips(std::size_t frames, std::size_t columns) {
  std::vector<std::uint8_t> strips(frames * columns);
  for (std::size_t i = 0; i < frames; ++i)
    for (std::size_t j = 0; j < columns; ++j)
      strips[i * columns + j] = static_cast<std::uint8_t>((i * 29 + 3) * j % (23 * i + 1) + i);
  return strips;
}

// Frame i's strip as a route keeps it: the 4-bit levels of its bytes, each within
// (range + 1) / 32 grey levels of the byte (dsp::PackStrip, tested against a quantiser of
// its own in tests/dsp), and the same whatever version the file is.
void ExpectStrips(const RouteFrames& frames, const std::vector<std::uint8_t>& taught,
                  std::size_t columns) {
  ASSERT_TRUE(frames.has_strips());
  std::vector<float> decoded(columns);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::vector<std::uint8_t> packed(frames.strip(i).begin(), frames.strip(i).end());
    ASSERT_EQ(packed.size(), 2 + (columns + 1) / 2);
    ASSERT_EQ(dsp::UnpackStrip(packed, decoded), dsp::HorizonStripError::kOk);
    const std::uint8_t* bytes = taught.data() + i * columns;
    const int lo = *std::min_element(bytes, bytes + columns);
    const int hi = *std::max_element(bytes, bytes + columns);
    EXPECT_EQ(int{packed.front()}, lo) << i;
    EXPECT_EQ(int{packed[1]}, hi - lo) << i;
    const float bound = static_cast<float>(hi - lo + 1) / 32.0f;
    for (std::size_t j = 0; j < columns; ++j)
      ASSERT_LE(std::fabs(decoded[j] - static_cast<float>(bytes[j])), bound) << i << "," << j;
  }
}

// Version 6 stores a horizon strip per frame after the descriptor, 4 bits a column with a
// byte minimum and range: they come back within the levels' bound, and the record grows
// by exactly 2 + columns / 2 bytes (an odd column count's last nibble is padding).
TEST_F(RouteDbTest, StripsRoundTripAndCostTheirColumnsPerFrame) {
  constexpr std::size_t kColumns = 25;
  RouteDbSettings settings = Settings();
  settings.strip = {static_cast<std::uint32_t>(kColumns), 16, 0, 2000};
  const std::vector<std::uint8_t> taught = TaughtStrips(10, kColumns);
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), settings, 4, true).ok());
    for (std::size_t i = 0; i < 10; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      ASSERT_TRUE(w.Append(meta, d, {taught.data() + i * kColumns, kColumns}).ok());
    }
    // A strip of the wrong length is an error, not a torn record.
    const std::uint8_t short_strip[3] = {};
    float d[kDim] = {};
    EXPECT_EQ(w.Append({}, d, short_strip).code(), StatusCode::kInvalidArgument);
    ASSERT_TRUE(w.Commit().ok());
  }
  EXPECT_EQ(Bytes().size(),
            kDataOffset + 4 * kRouteDbChunkHeaderBytes + 10 * (34 + 2 * kDim + 2 + 13));
  RouteFrames with_strips;
  ASSERT_TRUE(with_strips.Allocate(20, kDim, kColumns).ok());
  RouteDbLoadReport report;
  Status s = ParseRouteDb(Bytes(), &settings, RouteDbLoadPolicy::kStrict, &with_strips, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.settings.strip, settings.strip);
  EXPECT_EQ(report.strip_bits, 4u);
  ExpectFrames(with_strips, 10);
  ExpectStrips(with_strips, taught, kColumns);
  // The strip record names the encoding; version 6 has one, so another is damage, not a
  // strip to read some other way.
  std::vector<std::uint8_t> eight = Bytes();
  std::uint8_t* strip_record = eight.data() + kRouteDbHeaderBytes + kRouteDbLensRecordBytes;
  EXPECT_EQ(Load<std::uint32_t>(strip_record + 16), 4u);
  Store<std::uint32_t>(strip_record + 16, 8);
  Store<std::uint32_t>(strip_record + 28, Crc32({strip_record, 28}));
  s = ParseRouteDb(eight, &settings, RouteDbLoadPolicy::kStrict, &with_strips, &report);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_NE(std::string(s.message())
                .find("strip record: 8 bits a strip column, version 6 stores 4: the file is "
                      "corrupt"),
            std::string::npos)
      << s.message();
  // A configuration without heading loads the descriptors and ignores the strips.
  const RouteDbSettings no_heading = Settings();
  s = ParseRouteDb(Bytes(), &no_heading, RouteDbLoadPolicy::kStrict, &frames_, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  ExpectFrames(frames_, 10);
  EXPECT_FALSE(frames_.has_strips());
  // Another strip would give a wrong heading: refused, naming both.
  RouteDbSettings other = settings;
  other.strip.columns = 360;
  s = ParseRouteDb(Bytes(), &other, RouteDbLoadPolicy::kStrict, nullptr, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message())
                .find("taught with a 25-column horizon strip over 0.00..20.00 deg (16 rows), "
                      "this configuration has 360 columns"),
            std::string::npos)
      << s.message();
}

// Versions 4 and 5 stored a byte a column: their strips load packed, as a version-6 file's
// (one form in memory), and route info says 8 bits.
TEST_F(RouteDbTest, VersionFourAndFiveStripsArePackedOnLoad) {
  constexpr std::size_t kColumns = 148;
  RouteDbSettings settings = Settings();
  settings.strip = {static_cast<std::uint32_t>(kColumns), 16, 0, 2000};
  const std::vector<std::uint8_t> taught = TaughtStrips(11, kColumns);
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), settings, 4, true).ok());
    for (std::size_t i = 0; i < 11; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      ASSERT_TRUE(w.Append(meta, d, {taught.data() + i * kColumns, kColumns}).ok());
    }
    ASSERT_TRUE(w.Commit().ok());
  }
  RouteFrames v6;
  ASSERT_TRUE(v6.Allocate(20, kDim, kColumns).ok());
  ASSERT_TRUE(ParseRouteDb(Bytes(), &settings, RouteDbLoadPolicy::kStrict, &v6, nullptr).ok());
  for (std::uint32_t version : {4u, 5u}) {
    const std::vector<std::uint8_t> old = AsVersion(Bytes(), version, kColumns, taught);
    RouteFrames frames;
    ASSERT_TRUE(frames.Allocate(20, kDim, kColumns).ok());
    RouteDbLoadReport report;
    const Status s = ParseRouteDb(old, &settings, RouteDbLoadPolicy::kStrict, &frames, &report);
    ASSERT_TRUE(s.ok()) << "version " << version << ": " << s.message();
    EXPECT_EQ(report.version, version);
    EXPECT_EQ(report.strip_bits, 8u);
    EXPECT_EQ(old.size(), kDataOffset + 4 * kRouteDbChunkHeaderBytes +
                              11 * ((version == 5 ? 34 + 2 * kDim : 64 + 4 * kDim) + kColumns));
    ExpectFrames(frames, 11);
    ExpectStrips(frames, taught, kColumns);
    for (std::size_t i = 0; i < 11; ++i) {
      ASSERT_TRUE(std::equal(frames.strip(i).begin(), frames.strip(i).end(), v6.strip(i).begin(),
                             v6.strip(i).end()))
          << "version " << version << ", frame " << i;
    }
  }
}

// A version-3 file has no strips: it loads into a configuration that wants them, with
// has_strips() false (the firmware then reports no heading and says why once).
TEST_F(RouteDbTest, VersionThreeLoadsWithoutStrips) {
  Teach(9, 4, true);
  const std::vector<std::uint8_t> v3 = AsVersion(Bytes(), 3);
  EXPECT_EQ(v3.size() + kRouteDbStripRecordBytes, AsVersion(Bytes(), 4).size());
  RouteDbSettings want = Settings();
  want.strip = {360, 16, 0, 2000};
  RouteFrames frames;
  ASSERT_TRUE(frames.Allocate(20, kDim, 360).ok());
  RouteDbLoadReport report;
  Status s = ParseRouteDb(v3, &want, RouteDbLoadPolicy::kStrict, &frames, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.version, 3u);
  EXPECT_EQ(report.settings.strip.columns, 0u);
  EXPECT_TRUE(report.settings.lens.known);
  ExpectFrames(frames, 9);
  EXPECT_FALSE(frames.has_strips());
  EXPECT_TRUE(frames.strip(0).empty());
}

// Version 3 compares the lens parameters within tolerances and names what differs.
TEST_F(RouteDbTest, LensMismatchSaysWhatDiffers) {
  Teach(5, 10, true);
  RouteDbSettings want = Settings();
  // Within the tolerances: what a camera file written out with a few digits reads back as.
  want.lens.centre_x += 0.004;
  want.lens.fov_deg -= 0.005;
  want.lens.fx *= 1 + 1e-7;
  want.lens.k[0] *= 1 - 1e-7;
  Status s = ParseRouteDb(Bytes(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_TRUE(s.ok()) << s.message();

  want = Settings();
  want.lens.width = 160;
  want.lens.height = 120;
  want.lens.fov_deg = 180;
  want.lens.centre_x = 160;
  s = ParseRouteDb(Bytes(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  const std::string m = s.message();
  EXPECT_NE(m.find("lens differs (taught vs now): image size 320x240 vs 160x120; fov 185.00 vs "
                   "180.00 degrees; centre x 159.50 vs 160.00 px"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("use the camera file it was taught with, or teach again"), std::string::npos)
      << m;

  want = Settings();
  want.lens.model = 2;
  want.lens.k[1] = 0.5;
  want.lens.yaw_deg = 90;
  s = ParseRouteDb(Bytes(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_NE(std::string(s.message())
                .find("model equidistant vs kannala_brandt; k2 -0.002 vs 0.5; mount yaw 0.00 vs "
                      "90.00 degrees"),
            std::string::npos)
      << s.message();
}

// Every difference at once still fits the message, which keeps its fix.
TEST_F(RouteDbTest, LensMismatchMessageFitsWithEverythingDifferent) {
  RouteDbLens a = Settings().lens, b;
  b.known = true;
  b.model = 3;
  b.width = 1;
  b.ocam_hash = 5;
  b.roll_deg = b.pitch_deg = b.yaw_deg = 1e300;
  const Status s = CheckRouteDbLens(a, b);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find("model equidistant vs ocamcalib"), std::string::npos)
      << s.message();
  EXPECT_NE(std::string(s.message()).find("teach again"), std::string::npos) << s.message();
}

TEST_F(RouteDbTest, CapacityExceededIsReported) {
  Teach(30, 10, true);
  RouteFrames small;
  ASSERT_TRUE(small.Allocate(25, kDim).ok());
  const RouteDbSettings want = Settings();
  Status s = ParseRouteDb(Bytes(), &want, RouteDbLoadPolicy::kStrict, &small, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(std::string(s.message()).find("route_frames"), std::string::npos) << s.message();
}

TEST_F(RouteDbTest, NotARouteDatabase) {
  std::vector<std::uint8_t> text(200, 'x');
  EXPECT_EQ(Parse(text).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(Parse({}).code(), StatusCode::kDataLoss);
}

// Every truncation of a committed file is rejected, naming the chunk the cut falls in.
TEST_F(RouteDbTest, EveryTruncationIsRejectedNamingTheChunk) {
  constexpr std::size_t kFlush = 4;
  Teach(10, kFlush, true);  // chunks: 4, 4, 2 frames, then the commit record (chunk 4)
  const std::vector<std::uint8_t> full = Bytes();
  for (std::size_t len = 0; len < full.size(); ++len) {
    const std::vector<std::uint8_t> cut(full.begin(), full.begin() + static_cast<long>(len));
    Status s = Parse(cut);
    ASSERT_FALSE(s.ok()) << "loaded a file cut to " << len << " bytes";
    const std::string m = s.message();
    if (len < kDataOffset) {
      EXPECT_NE(m.find("header"), std::string::npos) << len << ": " << m;
      continue;
    }
    std::size_t k = 1;
    while (k < 4 && ChunkOffset(k + 1, kFlush, 10) <= len)
      ++k;
    if (len == ChunkOffset(k, kFlush, 10) || (k == 4 && len == ChunkOffset(4, kFlush, 10))) {
      // A cut exactly between chunks: the file ends cleanly but is not committed.
      EXPECT_NE(m.find("no commit record after chunk " + std::to_string(k - 1)), std::string::npos)
          << len << ": " << m;
    } else {
      EXPECT_NE(m.find("chunk " + std::to_string(k) + " at offset " +
                       std::to_string(ChunkOffset(k, kFlush, 10))),
                std::string::npos)
          << len << ": " << m;
    }
  }
}

// Every single-bit flip anywhere is rejected, naming the header or the damaged chunk.
TEST_F(RouteDbTest, EveryBitFlipIsRejectedNamingTheChunk) {
  constexpr std::size_t kFlush = 4;
  Teach(10, kFlush, true);
  const std::vector<std::uint8_t> good = Bytes();
  std::mt19937 rng(7);
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    std::vector<std::uint8_t> bad = good;
    bad[byte] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
    Status s = Parse(bad);
    ASSERT_FALSE(s.ok()) << "loaded a file with byte " << byte << " flipped";
    const std::string m = s.message();
    if (byte < kRouteDbHeaderBytes) {
      EXPECT_TRUE(m.find("header") != std::string::npos || m.find("magic") != std::string::npos ||
                  m.find("version") != std::string::npos)
          << byte << ": " << m;
      continue;
    }
    if (byte < kRouteDbHeaderBytes + kRouteDbLensRecordBytes) {
      EXPECT_NE(m.find("lens record (offset 64): checksum mismatch"), std::string::npos)
          << byte << ": " << m;
      continue;
    }
    if (byte < kDataOffset) {
      EXPECT_NE(m.find("strip record (offset 208): checksum mismatch"), std::string::npos)
          << byte << ": " << m;
      continue;
    }
    std::size_t k = 1;
    while (k < 4 && ChunkOffset(k + 1, kFlush, 10) <= byte)
      ++k;
    EXPECT_NE(m.find("chunk " + std::to_string(k) + " at offset " +
                     std::to_string(ChunkOffset(k, kFlush, 10))),
              std::string::npos)
        << byte << ": " << m;
    // Recovery must not hide damage followed by intact data. Only a damaged commit record
    // (the tail) may be dropped, and then every frame is there and the drop is reported.
    RouteDbLoadReport report;
    const bool recovered = Parse(bad, RouteDbLoadPolicy::kRecoverInterrupted, &report).ok();
    if (k < 4) {
      EXPECT_FALSE(recovered) << byte;
    } else {
      ASSERT_TRUE(recovered) << byte;
      EXPECT_FALSE(report.committed);
      EXPECT_EQ(report.dropped_bytes, kRouteDbChunkHeaderBytes);
      ExpectFrames(frames_, 10);
    }
  }
}

// Junk appended after a complete route is trailing bytes, not an interrupted teach: the
// strict load says so, info-style loading reports the route as committed, recover cuts
// the junk off.
TEST_F(RouteDbTest, TrailingBytesAfterTheCommitRecordAreNamedAsSuch) {
  Teach(25, 10, true);
  std::vector<std::uint8_t> bytes = Bytes();
  const std::size_t committed_size = bytes.size();
  bytes.insert(bytes.end(), 8, 0x5a);
  Status strict = Parse(bytes);
  ASSERT_FALSE(strict.ok());
  const std::string m = strict.message();
  EXPECT_NE(m.find("8 trailing bytes after the commit record at offset " +
                   std::to_string(committed_size)),
            std::string::npos)
      << m;
  EXPECT_EQ(m.find("interrupted"), std::string::npos) << m;
  RouteDbLoadReport report;
  ASSERT_TRUE(Parse(bytes, RouteDbLoadPolicy::kRecoverInterrupted, &report).ok());
  EXPECT_TRUE(report.committed);
  EXPECT_EQ(report.trailing_bytes, 8u);
  EXPECT_EQ(report.dropped_bytes, 0u);

  {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
  }
  ASSERT_TRUE(RecoverRouteDb(path_.c_str(), &report).ok());
  EXPECT_EQ(Bytes().size(), committed_size);
  ASSERT_TRUE(Parse(Bytes()).ok());
  ExpectFrames(frames_, 25);
}

// Damage in the middle (an intact chunk follows) names the chunk and its offset in one
// readable sentence and points at --salvage, which keeps the chunks before the damage
// (and the damaged original beside it); plain recover refuses and changes nothing.
TEST_F(RouteDbTest, MidFileDamageIsNamedAndSalvageKeepsTheChunksBefore) {
  Teach(30, 10, true);
  std::vector<std::uint8_t> bytes = Bytes();
  const std::size_t chunk2 = ChunkOffset(2, 10, 30);
  bytes[chunk2 + kRouteDbChunkHeaderBytes + 5] ^= 0x10;
  {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
  }
  Status s = LoadRouteDb(path_.c_str(), nullptr, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  ASSERT_FALSE(s.ok());
  std::string m = s.message();
  EXPECT_NE(m.find("chunk 2 at offset " + std::to_string(chunk2) + ": checksum mismatch"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("damaged mid-file"), std::string::npos) << m;
  EXPECT_NE(m.find("--salvage"), std::string::npos) << m;
  EXPECT_EQ(m.find(";:"), std::string::npos) << m;

  RouteDbLoadReport report;
  s = RecoverRouteDb(path_.c_str(), &report);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find("--salvage"), std::string::npos) << s.message();
  EXPECT_EQ(Bytes(), bytes) << "a refused recovery changed the file";

  s = RecoverRouteDb(path_.c_str(), &report, true);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(report.damaged_mid_file);
  EXPECT_EQ(report.frames, 10u);
  ASSERT_TRUE(Parse(Bytes()).ok());
  ExpectFrames(frames_, 10);
  std::ifstream kept(path_ + ".damaged", std::ios::binary);
  EXPECT_EQ(std::vector<std::uint8_t>(std::istreambuf_iterator<char>(kept),
                                      std::istreambuf_iterator<char>()),
            bytes);
}

// recover must not cut the chunk a running teach is appending: the writer holds a lock.
TEST_F(RouteDbTest, RecoverRefusesAFileATeachIsWriting) {
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 10, false).ok());
    for (std::size_t i = 0; i < 15; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      ASSERT_TRUE(w.Append(meta, d).ok());
    }
    const std::size_t size = Bytes().size();
    RouteDbLoadReport report;
    const Status s = RecoverRouteDb(path_.c_str(), &report);
    EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();
    EXPECT_NE(std::string(s.message()).find("running teach"), std::string::npos) << s.message();
    EXPECT_EQ(Bytes().size(), size);
  }
  // The writer closed without committing: now recovery may run.
  RouteDbLoadReport report;
  ASSERT_TRUE(RecoverRouteDb(path_.c_str(), &report).ok());
  EXPECT_EQ(report.frames, 10u);
}

// A FIFO (or device) as the route path is refused at once; opening it must not wait for
// a writer that never comes.
TEST_F(RouteDbTest, AFifoIsRefusedWithoutWaiting) {
  ASSERT_EQ(::mkfifo(path_.c_str(), 0600), 0);
  ::alarm(10);  // a hang fails the test instead of blocking ctest
  RouteDbLoadReport report;
  Status s =
      LoadRouteDb(path_.c_str(), nullptr, RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &report);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find("is a FIFO"), std::string::npos) << s.message();
  s = RecoverRouteDb(path_.c_str(), &report);
  EXPECT_NE(std::string(s.message()).find("is a FIFO"), std::string::npos) << s.message();
  ::alarm(0);
}

// Nothing intact to keep is a failure, not a "recovered: 0 frames" success.
TEST_F(RouteDbTest, RecoverWithNoIntactFrameIsAnError) {
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 10, false).ok());
  }
  const std::vector<std::uint8_t> before = Bytes();
  RouteDbLoadReport report;
  const Status s = RecoverRouteDb(path_.c_str(), &report);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss) << s.message();
  EXPECT_NE(std::string(s.message()).find("no intact frame"), std::string::npos) << s.message();
  EXPECT_EQ(Bytes(), before);
}

// A full disk during teach, simulated with RLIMIT_FSIZE in a child (no root, no mount):
// the 4th chunk does not fit, but the 32-byte commit record does, so the 30 frames already
// on the disk are committed and the 10 of the last chunk reported lost.
TEST_F(RouteDbTest, DiskFullDuringTeachCommitsTheFramesOnTheDisk) {
  // qemu-user spins at 100 % CPU in the forked child once the file limit is hit (measured:
  // 10 minutes without progress); cli.firmware_modes checks the same under the emulator
  // with `ulimit -f`, and the host build and the arm64 VM run this.
  if (skyloc::testing::UnderUserModeEmulator())
    GTEST_SKIP() << "qemu-user spins in a forked child past RLIMIT_FSIZE (support/emulator.h)";
  constexpr std::size_t kFlush = 10;
  const std::size_t limit = ChunkOffset(4, kFlush, 1000) + 100;  // 3 chunks + 100 bytes
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);  // EFBIG instead of death, as skyloc's handlers set it
    const rlimit lim{static_cast<rlim_t>(limit), static_cast<rlim_t>(limit)};
    if (::setrlimit(RLIMIT_FSIZE, &lim) != 0)
      ::_exit(2);
    RouteDbWriter w;
    if (!w.Create(path_.c_str(), Settings(), kFlush, false).ok())
      ::_exit(3);
    std::size_t i = 0;
    for (; i < 1000; ++i) {
      RouteFrameMeta meta;
      float d[kDim];
      FrameContent(i, &meta, d);
      if (!w.Append(meta, d).ok())
        break;
    }
    if (i != 39)  // the 40th frame's flush failed
      ::_exit(4);
    const Status s = w.Commit();
    if (s.ok() || !w.committed() || w.frames_durable() != 30 || w.frames_lost() != 10)
      ::_exit(5);
    ::_exit(0);
  }
  int wstatus = 0;
  ASSERT_EQ(::waitpid(child, &wstatus, 0), child);
  ASSERT_TRUE(WIFEXITED(wstatus)) << wstatus;
  ASSERT_EQ(WEXITSTATUS(wstatus), 0);
  const Status strict = Parse(Bytes());
  ASSERT_TRUE(strict.ok()) << strict.message();
  ExpectFrames(frames_, 30);
}

// The writer is killed with SIGKILL at a random moment while teaching, 20 times. The child
// reports through a pipe how many frames each completed Flush() made durable; after the
// kill the file must load (recovering the interrupted tail) with at least those frames,
// every one intact.
TEST_F(RouteDbTest, SurvivesKillDuringTeach) {
  std::mt19937 rng(20261121);
  for (int round = 0; round < 20; ++round) {
    std::remove(path_.c_str());
    const std::size_t flush_every = 1 + rng() % 16;
    const auto kill_after_us = static_cast<useconds_t>(rng() % 30000);
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::close(fds[0]);
      RouteDbWriter w;
      if (!w.Create(path_.c_str(), Settings(), flush_every, true).ok())
        ::_exit(3);
      for (std::size_t i = 0; i < 2000000; ++i) {
        RouteFrameMeta meta;
        float d[kDim];
        FrameContent(i, &meta, d);
        const std::uint64_t before = w.frames_durable();
        if (!w.Append(meta, d).ok())
          ::_exit(4);
        const std::uint64_t durable = w.frames_durable();
        if (durable != before && ::write(fds[1], &durable, sizeof durable) != sizeof durable)
          ::_exit(5);
      }
      ::_exit(0);
    }
    ::close(fds[1]);
    ::usleep(kill_after_us);
    ASSERT_EQ(::kill(child, SIGKILL), 0);
    int wstatus = 0;
    ASSERT_EQ(::waitpid(child, &wstatus, 0), child);
    ASSERT_TRUE(WIFSIGNALED(wstatus)) << "the child ended by itself (status " << wstatus << ")";
    std::uint64_t last_flushed = 0, v = 0;
    while (::read(fds[0], &v, sizeof v) == static_cast<ssize_t>(sizeof v))
      last_flushed = v;
    ::close(fds[0]);

    if (::access(path_.c_str(), F_OK) != 0) {
      // Killed before the atomic rename: there is no file, and nothing was flushed.
      EXPECT_EQ(last_flushed, 0u) << "round " << round;
      continue;
    }
    RouteDbLoadReport report;
    Status s = Parse(Bytes(), RouteDbLoadPolicy::kRecoverInterrupted, &report);
    ASSERT_TRUE(s.ok()) << "round " << round << ": " << s.message();
    EXPECT_GE(frames_.size(), last_flushed) << "round " << round;
    EXPECT_EQ(frames_.size() % flush_every, 0u) << "only whole chunks are kept";
    ExpectFrames(frames_, frames_.size());
    RecordProperty(
        "round_" + std::to_string(round),
        std::to_string(last_flushed) + " flushed, " + std::to_string(frames_.size()) + " loaded");
  }
}

// Every version this skyloc ever wrote (1 to 4: f32 descriptors and f64 poses, records
// rewritten by the documented layout) loads to the same frames as the version-5 file.
TEST_F(RouteDbTest, EveryOlderVersionLoadsTheSameFrames) {
  Teach(23, 6, true);
  for (std::uint32_t version = 1; version <= 5; ++version) {
    const std::vector<std::uint8_t> old = AsVersion(Bytes(), version);
    RouteDbLoadReport report;
    RouteDbSettings want = Settings();
    Status s = ParseRouteDb(old, &want, RouteDbLoadPolicy::kStrict, &frames_, &report);
    ASSERT_TRUE(s.ok()) << "version " << version << ": " << s.message();
    EXPECT_EQ(report.version, version);
    EXPECT_EQ(report.frames, 23u);
    ExpectFrames(frames_, 23);
  }
}

// Any descriptor (not one the codes hold exactly) comes back within the 16-bit codes'
// analytic bound (dsp/seqslam.h): half a step, a step below max / 32767.5, so within
// max / 65535 of what was taught. Timestamps exactly, poses to a float.
TEST_F(RouteDbTest, DescriptorsComeBackWithinTheCodesBound) {
  std::mt19937 rng(3u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<std::vector<float>> taught;
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 7, true).ok());
    for (std::size_t i = 0; i < 40; ++i) {
      std::vector<float> d(kDim);
      const float scale = std::ldexp(1.0f, static_cast<int>(i % 13) - 6);
      for (float& v : d)
        v = unit(rng) * scale;
      RouteFrameMeta meta;
      meta.timestamp_ns = 0xfedcba9876543210ull + i;
      meta.pose = drivers::Pose{1234.567, -89.001, 1.25, 3.3, -2.2, 179.9};
      ASSERT_TRUE(w.Append(meta, d).ok());
      taught.push_back(d);
    }
    ASSERT_TRUE(w.Commit().ok());
  }
  const RouteDbSettings want = Settings();
  ASSERT_TRUE(
      LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr).ok());
  ASSERT_EQ(frames_.size(), 40u);
  for (std::size_t i = 0; i < 40; ++i) {
    float max = 0;
    for (const float v : taught[i])
      max = std::max(max, v);
    for (std::size_t k = 0; k < kDim; ++k) {
      const double v = static_cast<double>(taught[i][k]), m = static_cast<double>(max);
      EXPECT_LE(std::fabs(static_cast<double>(frames_.descriptor(i)[k]) - v), m / 65535)
          << i << "," << k;
    }
    EXPECT_EQ(frames_.meta(i).timestamp_ns, 0xfedcba9876543210ull + i);
    ASSERT_TRUE(frames_.meta(i).pose.has_value());
    EXPECT_EQ(frames_.meta(i).pose->x_m, static_cast<double>(1234.567f));
    EXPECT_EQ(frames_.meta(i).pose->yaw_deg, static_cast<double>(179.9f));
  }
}

// Same bits on every target (tests/sim/same_bits_test.cpp): the bytes of a taught route,
// codes, exponents, float poses and checksums, hash to the value computed on x86-64. The
// aarch64 and armhf builds run this test too.
TEST_F(RouteDbTest, SameBitsOfATaughtRoute) {
  std::mt19937 rng(11u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  {
    RouteDbWriter w;
    ASSERT_TRUE(w.Create(path_.c_str(), Settings(), 8, true).ok());
    for (std::size_t i = 0; i < 30; ++i) {
      float d[kDim];
      for (float& v : d)
        v = unit(rng) * unit(rng);
      RouteFrameMeta meta;
      meta.timestamp_ns = 33333333ull * i;
      meta.pose = drivers::Pose{0.1 * static_cast<double>(i), -0.3, 1, 0.5, -1.5, 2.5};
      ASSERT_TRUE(w.Append(meta, d).ok());
    }
    ASSERT_TRUE(w.Commit().ok());
  }
  char crc[11];
  std::snprintf(crc, sizeof crc, "0x%08x", Crc32(Bytes()));
  EXPECT_EQ(std::string(crc), "0x610deb7c") << "the value is x86-64's";
}

// ---------------------------------------------------------------------------------------
// Loading a chunk at a time (issue 33): LoadRouteDb reads the file through RouteDbFile,
// the fuzz target and the tests above parse bytes in memory; one parser, so the file gives
// the same frames, reports and errors as its bytes.

// Every frame of `a` as in `b`: time, pose, descriptor and packed strip, bit for bit.
void ExpectSameFrames(const RouteFrames& a, const RouteFrames& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.has_strips(), b.has_strips());
  for (std::size_t i = 0; i < a.size(); ++i) {
    const RouteFrameMeta ma = a.meta(i), mb = b.meta(i);
    ASSERT_EQ(ma.timestamp_ns, mb.timestamp_ns) << i;
    ASSERT_EQ(ma.pose.has_value(), mb.pose.has_value()) << i;
    if (ma.pose) {
      const double pa[6] = {ma.pose->x_m,      ma.pose->y_m,       ma.pose->z_m,
                            ma.pose->roll_deg, ma.pose->pitch_deg, ma.pose->yaw_deg};
      const double pb[6] = {mb.pose->x_m,      mb.pose->y_m,       mb.pose->z_m,
                            mb.pose->roll_deg, mb.pose->pitch_deg, mb.pose->yaw_deg};
      for (std::size_t k = 0; k < 6; ++k)
        ASSERT_EQ(pa[k], pb[k]) << i << "," << k;
    }
    ASSERT_EQ(std::vector<float>(a.descriptor(i).begin(), a.descriptor(i).end()),
              std::vector<float>(b.descriptor(i).begin(), b.descriptor(i).end()))
        << i;
    ASSERT_EQ(std::vector<std::uint8_t>(a.strip(i).begin(), a.strip(i).end()),
              std::vector<std::uint8_t>(b.strip(i).begin(), b.strip(i).end()))
        << i;
  }
}

// `bytes` as the file at `path`, a new file: ext4 flushes a file truncated to zero when it
// is closed (auto_da_alloc), 3 ms a case in the table below.
void WriteNewFile(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::remove(path.c_str());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
}

void ExpectSameReport(const RouteDbLoadReport& a, const RouteDbLoadReport& b) {
  EXPECT_EQ(a.settings, b.settings);
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.strip_bits, b.strip_bits);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.chunks, b.chunks);
  EXPECT_EQ(a.committed, b.committed);
  EXPECT_EQ(a.valid_bytes, b.valid_bytes);
  EXPECT_EQ(a.dropped_bytes, b.dropped_bytes);
  EXPECT_EQ(a.damaged_mid_file, b.damaged_mid_file);
  EXPECT_EQ(a.trailing_bytes, b.trailing_bytes);
}

// The bytes allocated while a route loads are one chunk's payload and a few small things,
// the same for a route four times longer: reading the whole file first allocated the file.
// The frames are those the bytes parse to, and those taught.
TEST_F(RouteDbTest, LoadingAllocatesAChunkNotTheFile) {
  ASSERT_TRUE(AllocationCounterActive());
  constexpr std::size_t kColumns = 25, kFlush = 100;
  RouteDbSettings settings = Settings();
  settings.strip = {static_cast<std::uint32_t>(kColumns), 16, 0, 2000};
  const std::size_t payload = kFlush * RouteDbRecordBytes(kRouteDbVersion, kDim, kColumns);
  std::uint64_t allocated[2] = {};
  const std::size_t routes[2] = {3000, 12000};
  for (std::size_t r = 0; r < 2; ++r) {
    const std::size_t places = routes[r];
    const std::vector<std::uint8_t> taught = TaughtStrips(places, kColumns);
    {
      RouteDbWriter w;
      ASSERT_TRUE(w.Create(path_.c_str(), settings, kFlush, true).ok());
      for (std::size_t i = 0; i < places; ++i) {
        RouteFrameMeta meta;
        float d[kDim];
        FrameContent(i, &meta, d);
        ASSERT_TRUE(w.Append(meta, d, {taught.data() + i * kColumns, kColumns}).ok());
      }
      ASSERT_TRUE(w.Commit().ok());
    }
    RouteFrames loaded, parsed;
    ASSERT_TRUE(loaded.Allocate(places, kDim, kColumns).ok());
    ASSERT_TRUE(parsed.Allocate(places, kDim, kColumns).ok());
    RouteDbLoadReport load_report, parse_report;
    Status s;
    {
      const AllocationScope scope;
      s = LoadRouteDb(path_.c_str(), &settings, RouteDbLoadPolicy::kStrict, &loaded, &load_report);
      allocated[r] = scope.bytes();
    }
    ASSERT_TRUE(s.ok()) << s.message();
    const std::vector<std::uint8_t> bytes = Bytes();
    std::printf("%zu places, %zu-byte file, %zu-byte chunks: the load allocated %llu bytes\n",
                places, bytes.size(), payload, static_cast<unsigned long long>(allocated[r]));
    EXPECT_LE(allocated[r], payload + 1024) << places;
    s = ParseRouteDb(bytes, &settings, RouteDbLoadPolicy::kStrict, &parsed, &parse_report);
    ASSERT_TRUE(s.ok()) << s.message();
    ExpectSameReport(load_report, parse_report);
    EXPECT_EQ(load_report.frames, places);
    ExpectSameFrames(loaded, parsed);
    ExpectFrames(loaded, places);
    ExpectStrips(loaded, taught, kColumns);
  }
  EXPECT_EQ(allocated[0], allocated[1]) << "the load's memory grows with the route";
}

// Every damaged file of the tests above (each truncation, each byte with a bit flipped,
// junk after the commit record, a chunk header claiming 3.96 GB), under every policy:
// loading the file gives what parsing its bytes gives, errors word for word (after the
// path), reports field by field, frames bit for bit.
TEST_F(RouteDbTest, LoadingAFileAnswersAsParsingItsBytes) {
  constexpr std::size_t kFlush = 4;
  Teach(10, kFlush, true);
  const std::vector<std::uint8_t> good = Bytes();
  std::vector<std::vector<std::uint8_t>> cases;
  for (std::size_t len = 0; len <= good.size(); ++len)
    cases.emplace_back(good.begin(), good.begin() + static_cast<long>(len));
  std::mt19937 rng(7);
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    cases.push_back(good);
    cases.back()[byte] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
  }
  cases.push_back(good);
  cases.back().insert(cases.back().end(), 8, 0x5a);
  // Chunk 2's header (intact checksum) claiming 90,000,000 frames: 3,960,000,000 payload
  // bytes, which the file does not hold. Allocating them first would fail or take 4 GB.
  cases.push_back(good);
  {
    std::uint8_t* h = cases.back().data() + ChunkOffset(2, kFlush, 10);
    const std::uint32_t count = 90000000u;
    Store<std::uint32_t>(h + 16, count);
    Store<std::uint32_t>(
        h + 20, count * static_cast<std::uint32_t>(RouteDbRecordBytes(kRouteDbVersion, kDim, 0)));
    Store<std::uint32_t>(h + 28, Crc32({h, 28}));
  }
  const RouteDbSettings want = Settings();
  RouteFrames parsed;
  ASSERT_TRUE(parsed.Allocate(10000, kDim).ok());
  std::size_t loads_ok = 0, errors = 0;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::vector<std::uint8_t>& bytes = cases[c];
    WriteNewFile(path_, bytes);
    for (RouteDbLoadPolicy policy :
         {RouteDbLoadPolicy::kStrict, RouteDbLoadPolicy::kRecoverInterrupted,
          RouteDbLoadPolicy::kSalvage}) {
      RouteDbLoadReport load_report, parse_report;
      const Status loaded = LoadRouteDb(path_.c_str(), &want, policy, &frames_, &load_report);
      Status from_bytes = ParseRouteDb(bytes, &want, policy, &parsed, &parse_report);
      ASSERT_EQ(loaded.ok(), from_bytes.ok()) << c << ": " << loaded.message();
      if (!loaded.ok()) {
        ++errors;
        EXPECT_EQ(loaded.code(), from_bytes.code()) << c;
        from_bytes.AddContext("route database %s", path_.c_str());
        EXPECT_STREQ(loaded.message(), from_bytes.message()) << c;
        continue;
      }
      ++loads_ok;
      ExpectSameReport(load_report, parse_report);
      ExpectSameFrames(frames_, parsed);
    }
  }
  // The table holds both: a comparison of errors only could not fail on a frame.
  EXPECT_GT(loads_ok, 100u);
  EXPECT_GT(errors, 1000u);

  // The huge claim is refused as a truncated chunk, and nothing near it is allocated.
  WriteNewFile(path_, cases.back());
  const AllocationScope scope;
  const Status s =
      LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kSalvage, &frames_, nullptr);
  const std::uint64_t bytes = scope.bytes();
  EXPECT_TRUE(s.ok()) << s.message();  // salvage keeps chunk 1
  EXPECT_EQ(frames_.size(), kFlush);
  EXPECT_LT(bytes, 1u << 16);
  const Status strict =
      LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
  EXPECT_NE(
      std::string(strict.message())
          .find(
              "chunk 2 at offset " + std::to_string(ChunkOffset(2, kFlush, 10)) + ": truncated (" +
              std::to_string(good.size() - ChunkOffset(2, kFlush, 10) - kRouteDbChunkHeaderBytes) +
              " of 3960000000 payload bytes)"),
      std::string::npos)
      << strict.message();
}

// After damage the loader searches the rest of the file for an intact chunk header in
// windows of kRouteDbScanWindowBytes: one that lies across a window's edge is found, at the
// offset where the writer put it (ChunkOffset), and --salvage keeps the chunk before.
TEST_F(RouteDbTest, IntactDataAfterDamageIsFoundAcrossAScanWindowsEdge) {
  const std::size_t record = RouteDbRecordBytes(kRouteDbVersion, kDim, 0);
  const std::size_t around = kRouteDbScanWindowBytes / record;
  std::size_t across_edge = 0;
  for (std::size_t flush = around - 2; flush <= around + 2; ++flush) {
    Teach(3 * flush, flush, true);
    std::vector<std::uint8_t> bytes = Bytes();
    const std::size_t damaged = ChunkOffset(2, flush, 3 * flush);
    const std::size_t intact = ChunkOffset(3, flush, 3 * flush);
    // The search starts a byte after the damaged chunk's start; windows start every
    // kRouteDbScanWindowBytes - 31 bytes.
    const std::size_t in_first_window = intact - (damaged + 1);
    if (in_first_window < kRouteDbScanWindowBytes &&
        in_first_window + kRouteDbChunkHeaderBytes > kRouteDbScanWindowBytes)
      ++across_edge;
    bytes[damaged + kRouteDbChunkHeaderBytes + 7] ^= 0x01;
    WriteNewFile(path_, bytes);
    const RouteDbSettings want = Settings();
    Status s = LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kStrict, &frames_, nullptr);
    EXPECT_NE(
        std::string(s.message())
            .find("intact data follows at offset " + std::to_string(intact) + ": damaged mid-file"),
        std::string::npos)
        << flush << ": " << s.message();
    RouteDbLoadReport report;
    s = LoadRouteDb(path_.c_str(), &want, RouteDbLoadPolicy::kSalvage, &frames_, &report);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(report.damaged_mid_file);
    EXPECT_EQ(report.dropped_bytes, bytes.size() - damaged);
    ExpectFrames(frames_, flush);
  }
  EXPECT_GT(across_edge, 0u) << "no chunk header fell across a window's edge";
}

// A file cut while it is being read (its size was taken when it was opened) and a read
// error are errors naming the chunk and the offset, under every policy: neither is a torn
// tail that recovery may cut off.
TEST_F(RouteDbTest, AFileCutWhileBeingReadOrUnreadableIsAnError) {
  const std::size_t chunk2 = ChunkOffset(2, 10, 30);
  for (RouteDbLoadPolicy policy :
       {RouteDbLoadPolicy::kStrict, RouteDbLoadPolicy::kRecoverInterrupted,
        RouteDbLoadPolicy::kSalvage}) {
    Teach(30, 10, true);
    RouteDbFile file;
    ASSERT_TRUE(file.Open(path_.c_str()).ok());
    ASSERT_EQ(::truncate(path_.c_str(), static_cast<off_t>(chunk2 + 40)), 0);
    const Status s = ParseRouteDb(file, nullptr, policy, &frames_, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kDataLoss);
    EXPECT_NE(
        std::string(s.message())
            .find("chunk 2 at offset " + std::to_string(chunk2) + ": the file ends at offset " +
                  std::to_string(chunk2 + 40) + " but had " + std::to_string(file.size()) +
                  " bytes when opened: it was cut while being "
                  "read"),
        std::string::npos)
        << s.message();
  }

  // A source whose reads fail from chunk 3 on, as a disk's would.
  class FailingSource final : public RouteDbSource {
   public:
    FailingSource(RouteDbSource* inner, std::uint64_t from) : inner_(inner), from_(from) {}
    std::uint64_t size() const override { return inner_->size(); }
    Status Read(std::uint64_t offset, std::span<std::uint8_t> out) override {
      if (offset + out.size() > from_)
        return Status::FromErrno(EIO, "cannot read %zu bytes at offset %llu", out.size(),
                                 static_cast<unsigned long long>(offset));
      return inner_->Read(offset, out);
    }

   private:
    RouteDbSource* inner_;
    std::uint64_t from_;
  };
  Teach(30, 10, true);
  RouteDbFile file;
  ASSERT_TRUE(file.Open(path_.c_str()).ok());
  const std::size_t chunk3 = ChunkOffset(3, 10, 30);
  FailingSource failing(&file, chunk3);
  for (RouteDbLoadPolicy policy :
       {RouteDbLoadPolicy::kStrict, RouteDbLoadPolicy::kRecoverInterrupted,
        RouteDbLoadPolicy::kSalvage}) {
    const Status s = ParseRouteDb(failing, nullptr, policy, &frames_, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();  // EIO's
    EXPECT_NE(std::string(s.message())
                  .find("chunk 3 at offset " + std::to_string(chunk3) + ": cannot read"),
              std::string::npos)
        << s.message();
  }
  // The same file, read whole, loads.
  EXPECT_TRUE(ParseRouteDb(file, nullptr, RouteDbLoadPolicy::kStrict, &frames_, nullptr).ok());
  ExpectFrames(frames_, 30);
}

}  // namespace
}  // namespace skyloc::firmware
